"""The planner's nonlinear program and the ways it is solved.

- :mod:`~profileopt.planning.nlp.problem`: the NLP, built once per size and re-solved with parameters;
- :mod:`~profileopt.planning.nlp.solve`: one solve (the banded interior point, IPOPT);
- :mod:`~profileopt.planning.nlp.banded_ipm`: the banded interior-point method;
- :mod:`~profileopt.planning.nlp.pieces`: long routes solved in overlapping pieces.
"""
