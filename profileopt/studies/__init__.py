"""Studies that plan and verify many times: the four models side by side, the safety study,
and the real-route study.

- :mod:`~profileopt.studies.compare`: :func:`~profileopt.studies.compare.compare_models`;
- :mod:`~profileopt.studies.safety`: :func:`~profileopt.studies.safety.safety_study`;
- :mod:`~profileopt.studies.real_routes`: :func:`~profileopt.studies.real_routes.real_route_study`
  (GPS tracks, the LiDAR walk-through, hilly roads with kerbs, potholes and washboards, and the
  obstacle family of issue 29).
"""
