"""Physics: the quarter car's forces and the speeds that keep them within limits, knowing nothing of the planner.

- :mod:`~profileopt.physics.forces`: the four force models (Prev:BEM, IECM, SBEM:EF, SBEM:TF), written once in CasADi;
- :mod:`~profileopt.physics.speeds`: allowable speeds and speed bands of a model;
- :mod:`~profileopt.physics.wheel` and :mod:`~profileopt.physics.wheel_path`: the rigid wheel's path over the ground;
- :mod:`~profileopt.physics.ramps` and :mod:`~profileopt.physics.ramp_force`: steps in the wheel's path and their force bound;
- :mod:`~profileopt.physics.motion`: turns, grades, friction and drive power;
- :mod:`~profileopt.physics.quarter_car`: the exact response of the linear quarter car to a piecewise-linear input.
"""
