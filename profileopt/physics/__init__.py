"""Physics: the quarter car's forces and the speeds that keep them within limits, knowing nothing of the planner.

- :mod:`~profileopt.physics.forces`: the four force models (Prev:BEM, IECM, SBEM:EF, SBEM:TF), written once in CasADi;
- :mod:`~profileopt.physics.speeds`: allowable speeds and speed bands of a model;
- :mod:`~profileopt.physics.wheel`: the rigid wheel over the ground, at the samples and between them;
- :mod:`~profileopt.physics.steps`: steps met and drops landed by the wheel, and SBEM:TF's step limit;
- :mod:`~profileopt.physics.motion`: turns, grades, friction and drive power;
- :mod:`~profileopt.physics.rows`: the limits that couple speed and acceleration (friction circle, drive power);
- :mod:`~profileopt.physics.quarter_car`: the exact response of the linear quarter car to a piecewise-linear input;
- :mod:`~profileopt.physics.simulate`: the quarter car driven over a route's own samples at a profile's speeds.
"""
