"""Studies that plan and verify many times: the four models side by side, and the safety study.

- :mod:`~profileopt.studies.compare`: :func:`~profileopt.studies.compare.compare_models`;
- :mod:`~profileopt.studies.safety`: :func:`~profileopt.studies.safety.safety_study`.
"""
