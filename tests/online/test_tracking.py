"""The jerk-limited command under an envelope (profileopt.online.tracking)."""

from __future__ import annotations

import numpy as np
import pytest

from profileopt.online.tracking import jerk_limited_step

J, DT, A_MAX, D = 5.0, 0.1, 2.5, 4.0


def _envelope():
    """A hand-made envelope (m, m^2/s^2), piecewise linear in b = v^2: 12 m/s to 60 m, braking
    at D to 4 m/s (16 m later: (144 - 16) / (2 D)), 4 m/s to 100 m, braking at D to rest at
    102 m (16 / (2 D) = 2 m)."""
    knots = np.array([0.0, 60.0, 60.0 + (144.0 - 16.0) / (2 * D), 80.0, 100.0, 100.0 + 16.0 / (2 * D)])
    b = np.array([144.0, 144.0, 16.0, 16.0, 16.0, 0.0])
    return knots, b


def _drive(knots, b, s=0.0, v=0.0, a=0.0, cycles=400):
    states = [(s, v, a)]
    kept = []
    for _ in range(cycles):
        ahead = knots > s
        where = np.concatenate([[s], knots[ahead]])
        env = np.concatenate([[np.interp(s, knots, b)], b[ahead]])
        step = jerk_limited_step(s, v, a, where_m=where, envelope_b=env, max_accel_mps2=A_MAX,
                                 decel_mps2=np.full(where.size - 1, D), jerk_mps3=J, cycle_s=DT)
        kept.append(step.jerk_kept)
        states.append((step.position_m, step.speed_mps, step.accel_after_mps2))
        s, v, a = step.position_m, step.speed_mps, step.accel_after_mps2
        if v == 0.0 and s > 101.0:
            break
    return np.array(states), np.array(kept)


def test_the_vehicle_stays_under_the_envelope_with_the_jerk_bound_and_gets_close_to_it():
    knots, b = _envelope()
    states, kept = _drive(knots, b)
    s, v, a = states.T
    assert kept.all()
    moving = v[1:] > 0
    assert np.all(np.abs(np.diff(a))[moving] <= J * DT * (1 + 1e-9))
    assert np.all(a <= A_MAX + 1e-12) and np.all(a >= -D - 1e-12)
    # within each cycle b is linear in s (constant acceleration): check it on a fine grid
    for k in range(len(s) - 1):
        grid = np.linspace(s[k], s[k + 1], 20)
        b_line = np.interp(grid, [s[k], s[k + 1]], [v[k] ** 2, v[k + 1] ** 2]) if s[k + 1] > s[k] else grid * 0
        assert np.all(b_line <= np.interp(grid, knots, b) + 1e-9)
    assert v[s < 60].max() > 0.97 * 12.0  # close to the plateau before the drop
    assert v[(s > 82) & (s < 99)].min() > 0.97 * 4.0  # and to the lower one
    assert s[-1] <= 102.0 + 1e-9 and v[-1] == 0.0


def test_an_envelope_that_drops_under_the_vehicle_makes_it_brake_harder_and_say_so():
    """At 12 m/s, 5 m before a cap of 4 m/s (braking at D needs 16 m): no jerk-limited command
    stays under it, so the command brakes harder than the jerk bound and jerk_kept is False."""
    where = np.array([0.0, 5.0, 50.0])
    env = np.array([144.0, 16.0, 16.0])
    step = jerk_limited_step(0.0, 12.0, 0.0, where_m=where, envelope_b=env, max_accel_mps2=A_MAX,
                             decel_mps2=np.full(2, D), jerk_mps3=J, cycle_s=DT)
    assert not step.jerk_kept
    assert step.accel_mps2 == pytest.approx(-D)


def test_without_a_jerk_bound_it_follows_the_envelope_at_the_acceleration_bound():
    where = np.array([0.0, 100.0])
    env = np.array([400.0, 400.0])
    step = jerk_limited_step(0.0, 5.0, 0.0, where_m=where, envelope_b=env, max_accel_mps2=A_MAX,
                             decel_mps2=np.full(1, D), jerk_mps3=np.inf, cycle_s=DT)
    assert step.accel_mps2 == pytest.approx(A_MAX)
    assert step.speed_mps == pytest.approx(5.0 + A_MAX * DT)


def test_the_manoeuvres_deceleration_is_a_bound_of_every_piece_it_crosses():
    """Deceleration bounds falling from 4 to 0.05 m/s^2 over 200 m: the braking manoeuvre
    from 20 m/s may assume no more than the least bound of the pieces it crosses (checked by
    integrating the manoeuvre it describes)."""
    from profileopt.online.tracking import _manoeuvre_decel

    where = np.linspace(0.0, 2000.0, 2001)
    decel = np.interp(where[:-1], [0.0, 200.0, 2000.0], [4.0, 0.05, 0.05])
    d = float(_manoeuvre_decel(where, decel, np.array([0.0]), np.array([20.0]), np.array([0.0]), J)[0])
    ramp = d / J  # from a = 0 to -d
    stop_m = 20.0 * ramp - J * ramp**3 / 6.0 + (20.0 - 0.5 * J * ramp**2) ** 2 / (2.0 * d)
    crossed = decel[: int(np.ceil(stop_m)) + 1]
    assert d <= crossed.min() * (1 + 1e-12)
