"""``python -m ecdsim`` runs the command line."""

from ecdsim.cli.app import main

if __name__ == "__main__":
    main()
