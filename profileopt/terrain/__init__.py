"""Terrain: roughness, its windows and classes, synthetic profiles, and the geometry of a path.

- :mod:`~profileopt.terrain.roughness`: the Roughness Index (Eq. 1), roughness windows, e_max (Eq. 8);
- :mod:`~profileopt.terrain.window_sums`: prefix sums behind the sliding windows;
- :mod:`~profileopt.terrain.classes`: ISO 8608 roughness classes;
- :mod:`~profileopt.terrain.assumed`: an assumed roughness for terrain too coarse to measure;
- :mod:`~profileopt.terrain.synthetic`: synthetic elevation profiles (steps, washboards, ISO 8608);
- :mod:`~profileopt.terrain.geometry`: a route's smoothed path, curvature and grade;
- :mod:`~profileopt.terrain.ground_track`: the ground under the wheels along a GPS track over a terrain map.
"""
