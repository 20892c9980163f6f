"""The planner's nonlinear program and the ways it is solved.

- :mod:`~profileopt.planning.nlp.problem`: the NLP, built once per size and re-solved with parameters;
- :mod:`~profileopt.planning.nlp.solve`: one solve, by the back end the options name;
- :mod:`~profileopt.planning.nlp.backends`: the solver back ends (IPOPT, FATROP, the banded method);
- :mod:`~profileopt.planning.nlp.pieces`: long routes solved in overlapping pieces.
"""
