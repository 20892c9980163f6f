"""Verification: an independent check of a planned profile, from physics and the profile alone.

Nothing here imports :mod:`profileopt.planning`: a plan is judged by the vehicle's limits and
an exact simulation (:mod:`profileopt.physics.simulate`), never by the planner's own numbers.

- :mod:`~profileopt.verification.limit_check`: the vehicle's limits checked on paper;
- :mod:`~profileopt.verification.window_check`: the simulated force judged in every roughness window;
- :mod:`~profileopt.verification.verify`: :func:`~profileopt.verification.verify.verify`, all of these at once.
"""
