"""The event rules of the rigid mesh's event loops, shared by both of its paths.

The vectorised loop (:mod:`ecdsim.dynamics.solver`) and the single-case loop
(:mod:`ecdsim.dynamics.single`) must decide sticking, settling and the final speed by
the same numbers, so those numbers live here, once (docs/dynamics.md, the solver).
"""

from __future__ import annotations

# A breakaway needs the drive to exceed static friction by more than this relative margin;
# at the boundary (a forward motion that stops where drive = kinetic friction = static
# friction) rounding must not restart the motion: that would be numerical chatter.
STICK_MARGIN = 1e-12
# After an impact, a rebound whose kinetic energy is below this fraction of the first
# arrival's is taken as coming to rest against the stop (the remaining bounces form a
# convergent geometric series of vanishing energy).
SETTLE_FRACTION = 1e-12
# The statuses of a run that ends keeping its last speed (every other one ends at rest).
KEEPING_SPEED = ("latched", "stop_time", "event_limit", "horizon")
