"""The project's nouns: a route, a vehicle, a profile, and the arithmetic of stations along a route.

- :mod:`~profileopt.core.route`: :class:`~profileopt.core.route.Route`, the terrain along a path;
- :mod:`~profileopt.core.vehicle`: :class:`~profileopt.core.vehicle.Vehicle` and the bundled vehicle files;
- :mod:`~profileopt.core.profile`: :class:`~profileopt.core.profile.Profile`, a planned speed profile;
- :mod:`~profileopt.core.binding`: which limit holds the speed where;
- :mod:`~profileopt.core.segments`: a route cut into segments with their roughness;
- :mod:`~profileopt.core.path`: each segment's curvature and grade;
- :mod:`~profileopt.core.stations`: which samples belong to which segment;
- :mod:`~profileopt.core.kinematics`: time, acceleration and jerk between boundaries;
- :mod:`~profileopt.core.symbolic`: helpers that let one CasADi expression serve numbers and symbols;
- :mod:`~profileopt.core.checks`: argument checks shared by the public functions.
"""
