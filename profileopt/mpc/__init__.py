"""The force limits for other people's controllers: CasADi constraints, Functions and generated C.

- :mod:`~profileopt.mpc.constraints`: force constraints on your own decision variables;
- :mod:`~profileopt.mpc.horizon`: terrain envelopes between the grid points;
- :mod:`~profileopt.mpc.motion_constraints`: lateral and friction constraints of turns and hills;
- :mod:`~profileopt.mpc.functions`: named ``casadi.Function`` objects;
- :mod:`~profileopt.mpc.codegen`: C source of those Functions.
"""
