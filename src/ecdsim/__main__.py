"""``python -m ecdsim`` runs the command line."""

from ecdsim.cli.app import main

main()
