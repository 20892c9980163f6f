"""Allowable speeds: the generic safeguarded-Newton solver against closed-form inverses, the
SBEM:TF band semantics, edge cases, and the claims the paper makes about Figs. 5 and 6."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.special

from profileopt import MODELS, InputError, allowable_speed, force_n, get_model, load_vehicle, speed_bands
from profileopt.physics.speeds import (BAND_CHOICES, max_force_of_sets, max_force_over_segments, speed_bands_of_sets,
                                     speed_bands_reusing)
from profileopt.viz.figures import PAPER_AMPLITUDES_M, TERRAIN_FREQUENCY_CPM, sinusoid_terrain

ATV = load_vehicle("atv")
RES = load_vehicle("atv-resonant")
Z = math.sqrt(2) * scipy.special.erfinv(2 * 0.999999 - 1)  # Eq. (8) factor, 4.7534
# The paper's terrain (Section 4): 100 sinusoids at 1.5 cycles/m, amplitudes 0 to 0.1 m,
# RI from the sampled profiles (0 to 0.707 for h = 0.1 m).
FIG_RI = sinusoid_terrain(PAPER_AMPLITUDES_M, TERRAIN_FREQUENCY_CPM, 0.1).ri
FINE_RI = np.concatenate([FIG_RI, np.linspace(1e-4, 1.2, 301)])


# ------------------------------------------------------------ closed-form inverses (references)
# Written here only, independently of the library, from the paper and NOTES.md.

def _e_and_xw(ri, vehicle):
    e = Z * ri * vehicle.ground_clearance_m  # Eq. (8)
    ec = np.minimum(e, vehicle.wheel_radius_m)
    return e, np.sqrt(2 * ec * vehicle.wheel_radius_m - ec**2)  # Eq. (2), saturated at r


def _finish(v, ri, vehicle):
    # RI = 0: no force at all, so top speed; otherwise clip into [0, v_max]
    v = np.where(np.isnan(v), 0.0, v)
    return np.where(ri == 0, vehicle.max_speed_mps, np.clip(v, 0.0, vehicle.max_speed_mps))


def iecm_closed_form(ri, vehicle):
    # Eq. (7) with F_hat = F / k: V = (F_hat - e_max) wn X_w / (2 zeta e_max)
    k, wn, zeta = vehicle.spring_n_per_m, vehicle.natural_frequency_radps, vehicle.damping_ratio
    e, x_w = _e_and_xw(ri, vehicle)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = (vehicle.max_excitation_force_n / k - e) * wn * x_w / (2 * zeta * e)
    return _finish(v, ri, vehicle)


def sbem_ef_closed_form(ri, vehicle):
    # NOTES.md: V = (2 X_w / (pi c)) sqrt((F / e)^2 - k^2); 0 when F / e < k
    k, c = vehicle.spring_n_per_m, vehicle.damping_ns_per_m
    e, x_w = _e_and_xw(ri, vehicle)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = (vehicle.max_excitation_force_n / e) ** 2 - k**2
        v = 2 * x_w / (math.pi * c) * np.sqrt(np.maximum(q, 0.0))
    return _finish(v, ri, vehicle)


def prev_bem_closed_form(ri, vehicle):
    # NOTES.md: V = wn / (4 pi zeta f) sqrt((F / (k Y))^2 - 1), Y = sqrt(2) RI h; 0 when F < k Y
    k, wn, zeta = vehicle.spring_n_per_m, vehicle.natural_frequency_radps, vehicle.damping_ratio
    y = math.sqrt(2) * ri * vehicle.ground_clearance_m
    with np.errstate(divide="ignore", invalid="ignore"):
        q = (vehicle.max_excitation_force_n / (k * y)) ** 2 - 1
        v = wn / (4 * math.pi * zeta * vehicle.terrain_frequency_cpm) * np.sqrt(np.maximum(q, 0.0))
    return _finish(v, ri, vehicle)


CLOSED_FORMS = {"iecm": iecm_closed_form, "sbem_ef": sbem_ef_closed_form, "prev_bem": prev_bem_closed_form}


@pytest.mark.parametrize("band", ["first", "largest"])
@pytest.mark.parametrize("key", list(CLOSED_FORMS))
@pytest.mark.parametrize("vehicle", [ATV, RES, ATV.replace(max_excitation_force_n=800.0)], ids=["atv", "resonant", "weak"])
def test_newton_solver_matches_closed_form_inverse(vehicle, key, band):
    expected = CLOSED_FORMS[key](FINE_RI, vehicle)
    got = allowable_speed(FINE_RI, vehicle, model=key, band=band)
    # the grid must exercise every regime: top speed, interior root and 0
    assert np.any(expected == vehicle.max_speed_mps) and np.any((expected > 0) & (expected < vehicle.max_speed_mps))
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-10)


def test_hand_value_sbem_ef_inverse():
    # RI with e_max = 0.02 m (X_w = 0.06 m); limit 18 sqrt(5) N is the force at w_b = 6 rad/s
    # (test_forces), so the inverse must return V = 2 X_w w_b / pi = 0.72 / pi m/s.
    vehicle = ATV.replace(max_excitation_force_n=18.0 * math.sqrt(5.0))
    ri = 0.02 / (Z * 0.1)
    assert allowable_speed(ri, vehicle, model="sbem_ef") == pytest.approx(0.72 / math.pi, rel=1e-10)
    # IECM hand value: 218 N at 2 m/s (test_forces) -> limit 218 N gives 2 m/s
    assert allowable_speed(ri, ATV.replace(max_excitation_force_n=218.0), model="iecm") == pytest.approx(2.0, rel=1e-10)


# ------------------------------------------------------------ SBEM:TF (no closed form)

@pytest.mark.parametrize("vehicle", [ATV, RES], ids=["atv", "resonant"])
def test_sbem_tf_first_and_largest_are_what_they_claim(vehicle):
    limit = vehicle.max_transmitted_force_n
    vmax = vehicle.max_speed_mps
    ris = FIG_RI[1::3]
    first = allowable_speed(ris, vehicle, model="sbem_tf", band="first")
    largest = allowable_speed(ris, vehicle, model="sbem_tf", band="largest")
    assert np.all(first <= largest)
    for v in (first, largest):  # an interior answer is a root: the force equals the limit
        interior = (v > 0) & (v < vmax)
        np.testing.assert_allclose(force_n(v[interior], vehicle, ri=ris[interior], model="sbem_tf"), limit, rtol=1e-9)
    # "first": every speed from rest up to it is admissible (a fine grid, far finer than the
    # resonance peak, whose relative width is ~ zeta), and just above it is not
    unit = np.linspace(0.0, 1.0, 4001)[None, :]
    below = first[:, None] * unit
    assert np.all(force_n(below, vehicle, ri=ris[:, None], model="sbem_tf") <= limit * (1 + 1e-9))
    short = first < vmax
    assert np.all(force_n(first[short] * (1 + 1e-6) + 1e-9, vehicle, ri=ris[short], model="sbem_tf") > limit)
    # "largest": no speed above it, up to v_max, is admissible
    above = largest[:, None] + (vmax - largest[:, None]) * unit[:, 1:]
    short = largest < vmax
    assert np.all(force_n(above[short], vehicle, ri=ris[short, None], model="sbem_tf") > limit)


@pytest.mark.parametrize("key", list(MODELS))
@pytest.mark.parametrize("vehicle", [ATV, RES], ids=["atv", "resonant"])
def test_every_band_edge_is_a_root(key, vehicle):
    # Regression: a Newton iterate that hit a root exactly (f == 0) was replaced by the
    # bracket midpoint (SBEM:TF, atv-resonant, RI = 0.154 gave 0.33725 m/s, a speed where
    # the force is 3 % below the limit, instead of the root 0.34175 m/s).
    ri = np.linspace(1e-3, 0.8, 800)
    bands = speed_bands(ri, vehicle, model=key)
    limit = get_model(key).limit_n(vehicle)
    rows = np.broadcast_to(ri[:, None], bands.lower_mps.shape)
    for edges in (bands.lower_mps, bands.upper_mps):
        interior = np.isfinite(edges) & (edges > 0) & (edges < vehicle.max_speed_mps)
        np.testing.assert_allclose(force_n(edges[interior], vehicle, ri=rows[interior], model=key), limit, rtol=1e-9)
    # Reference: Eq. (13) set equal to 1000 N and solved independently with scipy's brentq on
    # [0.2, 0.4] m/s for atv-resonant at RI 0.154 (e_max = 4.7534 * 0.154 * 0.1 m): 0.3417451789.
    assert allowable_speed(0.154, RES, model="sbem_tf", band="first") == pytest.approx(0.34174518, rel=1e-6)


def test_sbem_tf_table_1_is_monotone_so_semantics_agree():
    np.testing.assert_array_equal(
        allowable_speed(FINE_RI, ATV, model="sbem_tf", band="first"), allowable_speed(FINE_RI, ATV, model="sbem_tf", band="largest")
    )


# ------------------------------------------------------------ edge cases

@pytest.mark.parametrize("band", ["first", "largest"])
@pytest.mark.parametrize("key", list(MODELS))
def test_smooth_ground_allows_top_speed(key, band):
    assert allowable_speed(0.0, RES, model=key, band=band) == RES.max_speed_mps
    np.testing.assert_array_equal(allowable_speed(np.zeros(3), ATV, model=key, band=band), ATV.max_speed_mps)


@pytest.mark.parametrize("band", ["first", "largest"])
@pytest.mark.parametrize("key", ["prev_bem", "iecm", "sbem_ef"])
def test_limit_below_static_force_gives_zero(key, band):
    # RI = 0.5: static forces k e_max = 900 * 0.2377 = 214 N (IECM, SBEM:EF) and
    # k Y = 900 * 0.0707 = 63.6 N (Prev:BEM) both exceed a 10 N limit
    weak = ATV.replace(max_excitation_force_n=10.0)
    assert allowable_speed(0.5, weak, model=key, band=band) == 0.0
    assert speed_bands(0.5, weak, model=key).count[0] == 0


def test_sbem_tf_has_no_static_force():
    # F_T ~ k e r^2 as V -> 0: even a tiny limit leaves a small positive speed
    v = allowable_speed(0.5, ATV.replace(max_transmitted_force_n=1.0), model="sbem_tf")
    assert 0 < v < 0.1
    assert force_n(v, ATV, ri=0.5, model="sbem_tf") == pytest.approx(1.0, rel=1e-9)


@pytest.mark.parametrize("ri", [math.nan, -0.1, [0.1, math.nan], [-1e-12]])
def test_nan_or_negative_ri_raises(ri):
    with pytest.raises(ValueError, match="RI"):
        allowable_speed(ri, ATV)


def test_bad_model_and_semantics_raise():
    with pytest.raises(ValueError, match="largest"):
        allowable_speed(0.1, ATV, model="sbem_tf", band="last")
    with pytest.raises(ValueError, match="sbem_tf"):
        allowable_speed(0.1, ATV, model="sbem")


def test_shapes_scalar_and_array():
    assert isinstance(allowable_speed(0.3, ATV), float)
    grid = np.array([[0.0, 0.1], [0.3, 0.7]])
    out = allowable_speed(grid, ATV, model="iecm")
    assert out.shape == (2, 2)
    np.testing.assert_allclose(out, iecm_closed_form(grid, ATV), rtol=1e-9)


# ------------------------------------------------------------ the paper's claims (Figs. 5, 6)

def test_fig5_ordering_prev_bem_iecm_sbem_ef():
    # "the method derived in [11] produces the most aggressive velocity profile ... IECM had a
    # more aggressive velocity profile than the two SBEM methods"
    prev, iecm, ef = (allowable_speed(FIG_RI, ATV, model=k) for k in ("prev_bem", "iecm", "sbem_ef"))
    assert np.all(prev >= iecm - 1e-12)
    assert np.all(iecm >= ef - 1e-12)
    assert np.any(prev > iecm + 1) and np.any(iecm > ef + 1)  # not trivially equal


def test_fig5_sbem_ef_and_tf_almost_identical():
    # "SBEM:EF and SBEM:TF produced almost identical profiles": within 0.5 %
    ef = allowable_speed(FIG_RI, ATV, model="sbem_ef")
    tf = allowable_speed(FIG_RI, ATV, model="sbem_tf")
    np.testing.assert_allclose(tf, ef, rtol=0.005)
    assert ef.min() < 4.0  # the comparison covers the slow, rough end too


def test_fig6_largest_follows_ef_then_collapses_at_ri_045():
    # "With resonance ... SBEM:TF deviates significantly from SBEM:EF, especially starting at
    # RI ~ 0.45" (NOTES.md: this is the "largest" root)
    ef = allowable_speed(FIG_RI, RES, model="sbem_ef")
    tf = allowable_speed(FIG_RI, RES, model="sbem_tf", band="largest")
    near = FIG_RI <= 0.36
    np.testing.assert_allclose(tf[near], ef[near], rtol=0.05)
    upto = FIG_RI <= 0.40
    np.testing.assert_allclose(tf[upto], ef[upto], rtol=0.10)
    collapsed = (FIG_RI >= 0.45) & (FIG_RI <= 0.55)
    assert collapsed.sum() >= 10
    assert np.all(tf[collapsed] < 0.5 * ef[collapsed])


def test_fig6_first_collapses_from_ri_013():
    # NOTES.md: the first crossing (every speed from rest admissible) collapses to the band
    # below resonance, about 0.3 m/s, already from RI ~ 0.13 on
    first = allowable_speed(FIG_RI, RES, model="sbem_tf", band="first")
    assert np.all(first[FIG_RI >= 0.13] < 0.4)
    assert np.all(first[FIG_RI >= 0.13] > 0.2)
    assert np.all(first[FIG_RI <= 0.1] > 8.0)  # and it really is a collapse


# ------------------------------------------------------------------ one vocabulary (issue 9)

def test_band_choices_and_all_is_refused_by_allowable_speed():
    assert BAND_CHOICES == ("first", "largest", "all")
    with pytest.raises(InputError, match="speed_bands"):
        allowable_speed(0.3, RES, band="all")
    with pytest.raises(InputError, match="band 'last'"):
        allowable_speed(0.3, RES, band="last")
    with pytest.raises(TypeError):
        allowable_speed(0.3, RES, semantic="first")  # a misspelt keyword


def test_largest_band_only_keeps_the_top_band():
    ri = np.array([0.0, 0.3, 0.5])
    bands = speed_bands(ri, RES.replace(max_transmitted_force_n=1000.0))
    weak = speed_bands(np.array([0.5]), ATV.replace(max_excitation_force_n=10.0), model="iecm")
    assert bands.count.max() >= 2 and weak.count[0] == 0  # several bands, and none at all
    top = bands.largest_band_only()
    np.testing.assert_array_equal(top.count, np.minimum(bands.count, 1))
    np.testing.assert_array_equal(top.upper_mps[:, 0], bands.largest())
    np.testing.assert_array_equal(top.largest(), bands.largest())
    last = bands.count - 1
    np.testing.assert_array_equal(top.lower_mps[:, 0], bands.lower_mps[np.arange(3), last])
    empty = weak.largest_band_only()
    assert empty.count[0] == 0 and np.isnan(empty.lower_mps[0, 0]) and empty.largest()[0] == 0.0
    np.testing.assert_array_equal(bands.first_band_only().first(), bands.first())


# ------------------------------------------------------------ each distinct terrain value once

def _row(bands, k):
    """Row k of a SpeedBands without its NaN padding: (lower, upper, peaks)."""
    count = int(bands.count[k])
    peaks = bands.peaks_mps[k]
    return bands.lower_mps[k, :count], bands.upper_mps[k, :count], peaks[~np.isnan(peaks)]


@pytest.mark.parametrize("vehicle, model", [(RES, "sbem_tf"), (ATV, "sbem_tf"), (RES, "iecm")])
def test_speed_bands_reusing_gives_each_row_what_it_gives_alone(vehicle, model):
    # Reference: every row in a call of its own (no batch, no shared value, no memo). With
    # atv-resonant every RI here is rough enough that even a crawl reaches the limit, so the
    # RI range form is used alone and together (speed_bands decides it per call); atv and
    # the monotone IECM use the plain form throughout. Repeated values on purpose.
    rng = np.random.default_rng(5)
    ri = rng.choice(np.linspace(0.06, 0.6, 12), 60)
    ri_min = ri * rng.choice([0.5, 0.8, 1.0], 60)
    first, memo = speed_bands_reusing(ri[:40], vehicle, model=model, ri_min=ri_min[:40])
    second, _ = speed_bands_reusing(ri[20:], vehicle, model=model, ri_min=ri_min[20:], memo=memo)
    for bands, rows in ((first, range(0, 40)), (second, range(20, 60))):
        assert bands.count.shape == (len(rows),)
        for k, i in enumerate(rows):
            alone = speed_bands([ri[i]], vehicle, model=model, ri_min=[ri_min[i]])
            for got, want in zip(_row(bands, k), _row(alone, 0)):
                np.testing.assert_array_equal(got, want)
        # the padding is what a single call makes: as wide as the widest row, at least 1
        assert bands.lower_mps.shape[1] == max(int(bands.count.max()), 1)
        assert not np.all(np.isnan(bands.peaks_mps[:, -1])) or bands.peaks_mps.shape[1] == 1


def test_speed_bands_reusing_finds_only_values_it_has_not_seen(monkeypatch):
    import profileopt.physics.speeds as speeds

    again = np.array([0.4, 0.5, 0.1, 0.5])
    reference = speed_bands(again, RES, ri_min=0.5 * again)  # before counting
    computed = []
    real = speeds._speed_bands

    def counting(terrain, vehicle, model):
        computed.append(terrain[-1].size)
        return real(terrain, vehicle, model)

    monkeypatch.setattr(speeds, "_speed_bands", counting)
    ri = np.array([0.1, 0.2, 0.2, 0.3, 0.1, 0.4])
    _, memo = speed_bands_reusing(ri, RES, ri_min=0.5 * ri)
    assert computed == [4]  # 0.1, 0.2, 0.3, 0.4 (with their ranges) once each
    bands, _ = speed_bands_reusing(again, RES, ri_min=0.5 * again, memo=memo)
    assert computed == [4, 1]  # only 0.5 is new
    for k in range(again.size):
        for got, want in zip(_row(bands, k), _row(reference, k)):
            np.testing.assert_array_equal(got, want)
    # another vehicle object (equal or not), or another model: nothing is taken from the memo
    import dataclasses
    speed_bands_reusing(again, dataclasses.replace(RES), ri_min=0.5 * again, memo=memo)
    speed_bands_reusing(again, RES, model="sbem_ef", ri_min=0.5 * again, memo=memo)
    assert computed == [4, 1, 3, 3]


def test_speed_bands_of_no_terrain_is_empty_and_its_memo_harmless():
    bands, memo = speed_bands_reusing(np.empty(0), RES)
    assert bands.count.shape == (0,) and bands.lower_mps.shape[0] == 0
    after, _ = speed_bands_reusing([0.2, 0.3], RES, memo=memo)
    reference = speed_bands([0.2, 0.3], RES)
    np.testing.assert_array_equal(after.upper_mps, reference.upper_mps)


# ------------------------------------------------------------ sets of RIs (the windows of a segment)

def _set_force(speed, members, vehicle):
    """The largest SBEM:TF force over the members' RIs at each speed (brute force), N."""
    speed = np.atleast_1d(speed)
    return np.max([force_n(speed, vehicle, ri=np.full(speed.size, r)) for r in members], axis=0)


def _random_sets(seed):
    # windows of smooth and rough ground mixed, zero RIs (flat windows) included
    rng = np.random.default_rng(seed)
    values = np.abs(rng.normal(0.1, 0.12, 240))
    values[rng.uniform(size=values.size) < 0.2] = 0.0
    first = rng.integers(0, values.size - 1, 40)
    return values, first, np.minimum(first + rng.integers(1, 25, first.size), values.size)


@pytest.mark.parametrize("seed", [0, 1])
def test_bands_of_sets_are_the_speeds_admissible_for_every_member(seed) -> None:
    # Reference: a dense grid of speeds, admissible where every member's force is within the
    # limit; band edges may differ from it only within a grid step of an edge
    values, first, stop = _random_sets(seed)
    bands, _ = speed_bands_of_sets(values, first, stop, RES)
    limit = RES.max_transmitted_force_n
    grid = np.concatenate([np.linspace(0.0, 3.0, 6001), np.linspace(3.0, RES.max_speed_mps, 341)[1:]])
    looser = speed_bands([values[a:b].max() for a, b in zip(first, stop)], RES,
                         ri_min=[values[a:b].min() for a, b in zip(first, stop)])
    gained = 0
    for i in range(first.size):
        admissible = _set_force(grid, values[first[i]:stop[i]], RES) <= limit
        inside = np.zeros(grid.size, dtype=bool)
        for j in range(int(bands.count[i])):
            inside |= (grid >= bands.lower_mps[i, j]) & (grid <= bands.upper_mps[i, j])
        edges = np.concatenate([bands.lower_mps[i, :bands.count[i]], bands.upper_mps[i, :bands.count[i]]])
        wrong = grid[admissible != inside]
        assert all(np.min(np.abs(edges - v), initial=np.inf) < 1e-3 for v in wrong), (i, wrong[:4])
        # never looser than every member's own bands; often faster than the bound over the RI range
        assert bands.first()[i] >= looser.first()[i] - 1e-12
        gained += bands.first()[i] > looser.first()[i] * 1.01
    assert gained >= 5  # the reason for sets: the range's bound forbids speeds no member reaches the limit at


def test_max_force_of_sets_is_the_largest_over_members_and_speeds() -> None:
    values, first, stop = _random_sets(2)
    rng = np.random.default_rng(5)
    bands, memo = speed_bands_of_sets(values, first, stop, RES)
    edge = bands.first()
    for i in range(first.size):
        # a random interval, and one ending at the set's first band edge (where the member that
        # sets the edge, often not the largest RI, is at the limit)
        speed = rng.uniform(0.0, 2.0, 2) if i % 2 or edge[i] == RES.max_speed_mps else np.array([0.8, 1.0]) * edge[i]
        dense = np.linspace(speed.min(), speed.max(), 4001)
        reference = _set_force(dense, values[first[i]:stop[i]], RES).max()
        for given in (memo, None):
            got = max_force_of_sets(values, first[i:i + 1], stop[i:i + 1], speed, RES, memo=given)[0]
            # never below the brute force (which only samples the interval), and at most its grid step above
            assert reference * (1 - 1e-12) <= got <= reference * (1 + 1e-3)


def test_sets_of_a_force_growing_with_the_ri_are_their_largest_ri() -> None:
    values, first, stop = _random_sets(3)
    top = np.array([values[a:b].max() for a, b in zip(first, stop)])
    for vehicle, model in ((RES, "iecm"), (ATV, "sbem_tf")):  # the atv's crawl bound is within its limit
        sets, _ = speed_bands_of_sets(values, first, stop, vehicle, model=model)
        plain = speed_bands(top, vehicle, model=model)
        np.testing.assert_array_equal(sets.count, plain.count)
        np.testing.assert_array_equal(sets.upper_mps, plain.upper_mps)
        speed = np.linspace(0.1, 9.0, first.size + 1)
        np.testing.assert_array_equal(max_force_of_sets(values, first, stop, speed, vehicle, model=model),
                                      max_force_over_segments(model, vehicle, top, speed, plain.peaks_mps))


@pytest.mark.parametrize("block", [1, 7, 50])
def test_sets_in_blocks_of_pairs_are_the_sets_at_once(monkeypatch, block) -> None:
    """The (set, member) pairs are intersected a block of sets at a time (PAIR_BLOCK pairs, or
    one set): each set's bands, peaks and largest force are its own, so any block size gives
    the same arrays as one block (the random sets: about 40 sets of up to 24 members)."""
    import profileopt.physics.speeds as speeds

    values, first, stop = _random_sets(4)
    speed = np.linspace(0.1, 9.0, first.size + 1)
    whole, _ = speed_bands_of_sets(values, first, stop, RES)
    whole_force = max_force_of_sets(values, first, stop, speed, RES)
    monkeypatch.setattr(speeds, "PAIR_BLOCK", block)
    parts, _ = speed_bands_of_sets(values, first, stop, RES)
    for name in ("lower_mps", "upper_mps", "count", "peaks_mps"):
        np.testing.assert_array_equal(getattr(parts, name), getattr(whole, name))
    np.testing.assert_array_equal(max_force_of_sets(values, first, stop, speed, RES), whole_force)
    assert whole.count.sum() > first.size  # sets with more than one band: the intersections matter
