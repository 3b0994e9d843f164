"""Kinematics from Python: the scalar solvers against the CLI's JSON for the showcase, the batch
kernels against the loop-closure equations (an independent formulation in NumPy), zero-copy
(tracemalloc sees no allocation proportional to the batch), statuses instead of NaN, bad input
raising exceptions that name the problem, and the GIL released during a batch."""
import math
import threading
import time
import tracemalloc

import numpy as np
import pytest

import fivebar
from conftest import SHOWCASE, run_cli

RNG_SEED = 20221023


def assert_same(a, b, where):
    """Equal documents, numbers to 1e-9 (the CLI converts degrees itself)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{k}]")
    elif isinstance(a, float) or isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9), where
    else:
        assert a == b, where


def random_angles(n, seed=RNG_SEED):
    rng = np.random.default_rng(seed)
    return rng.uniform(-math.pi, math.pi, n), rng.uniform(-math.pi, math.pi, n)


@pytest.mark.parametrize("station,mechanism,theta_deg", [
    ("index", "lower", (100.0, 80.0)), ("index", "upper", (-100.0, -80.0)), ("thumb", "lower", (120.0, 60.0))])
def test_fk_equals_cli_json(showcase, station, mechanism, theta_deg):
    doc = run_cli("fk", SHOWCASE, "--station", station, "--mechanism", mechanism,
                  "--theta", f"{theta_deg[0]},{theta_deg[1]}", "--json")
    m = showcase.station(station).mechanism(mechanism)
    pose = fivebar.fk(m, math.radians(theta_deg[0]), math.radians(theta_deg[1]))
    assert pose.status.name == doc["status"]
    if doc["status"] == "unreachable":
        return
    assert pose.P == pytest.approx(tuple(doc["point_mm"]), abs=1e-12)
    assert np.degrees([pose.theta1, pose.theta2]) == pytest.approx(doc["theta_deg"], abs=1e-10)
    assert pose.lci == pytest.approx(doc["lci"], rel=1e-12)
    assert np.asarray(pose.J) == pytest.approx(np.asarray(doc["jacobian"]), abs=1e-10)
    # to_dict() is the pose part of the CLI's document, key for key.
    for k, v in pose.to_dict().items():
        assert_same(doc[k], v, k)


@pytest.mark.parametrize("point", [(6.25, 12.0), (4.0, 16.0), (60.0, 60.0)])
def test_ik_equals_cli_json(showcase, index_lower, point):
    doc = run_cli("ik", SHOWCASE, "--station", "index", "--mechanism", "lower", "--point",
                  f"{point[0]},{point[1]}", "--json")
    pose = fivebar.ik(index_lower, *point)
    assert pose.status.name == doc["status"]
    if doc["status"] != "unreachable":
        assert np.degrees([pose.theta1, pose.theta2]) == pytest.approx(doc["theta_deg"], abs=1e-10)
        assert pose.lci == pytest.approx(doc["lci"], rel=1e-12)


def test_fk_batch_closes_the_loop(index_lower):
    """|A1 - P| = L3 and |A2 - P| = L4 where ok, computed here from the returned points alone."""
    t1, t2 = random_angles(100_000)
    x, y, status = fivebar.fk(index_lower, t1, t2)
    assert x.dtype == np.float64 and status.dtype == np.uint8 and x.shape == t1.shape
    assert np.isfinite(x).all() and np.isfinite(y).all()
    (o1x, o1y), (o2x, o2y) = index_lower.O1, index_lower.O2
    L1, L2, L3, L4 = index_lower.links
    ok = status == int(fivebar.Status.ok)
    assert 0.5 < ok.mean() < 1.0  # both outcomes are exercised
    a1 = np.stack([o1x + L1 * np.cos(t1), o1y + L1 * np.sin(t1)])
    a2 = np.stack([o2x + L2 * np.cos(t2), o2y + L2 * np.sin(t2)])
    p = np.stack([x, y])
    scale = index_lower.length_scale
    assert np.abs(np.hypot(*(p - a1))[ok] - L3).max() < 1e-9 * scale
    assert np.abs(np.hypot(*(p - a2))[ok] - L4).max() < 1e-9 * scale
    # Unreachable: no configuration, zeros (never NaN).
    unreachable = status == int(fivebar.Status.unreachable)
    assert unreachable.any() and (x[unreachable] == 0).all()
    # The design's assembly side ("+": tactor above A1A2).
    cross = (a2[0] - a1[0]) * (p[1] - a1[1]) - (a2[1] - a1[1]) * (p[0] - a1[0])
    assert (cross[ok] > 0).all()


def test_batch_equals_scalar_and_ik_inverts_fk(index_lower):
    t1, t2 = random_angles(2000, seed=7)
    x, y, status = fivebar.fk(index_lower, t1, t2)
    for k in range(0, 2000, 97):
        pose = fivebar.fk(index_lower, t1[k], t2[k])
        assert int(pose.status) == status[k]
        if pose.status == fivebar.Status.ok:
            assert (x[k], y[k]) == pytest.approx(pose.P, abs=1e-11)
    ok = status == int(fivebar.Status.ok)
    # The realised working mode, from the geometry: sign of cross(A_i - O_i, P - A_i) per leg.
    (o1x, o1y), (o2x, o2y) = index_lower.O1, index_lower.O2
    L1, L2, _, _ = index_lower.links
    a1x, a1y = o1x + L1 * np.cos(t1), o1y + L1 * np.sin(t1)
    a2x, a2y = o2x + L2 * np.cos(t2), o2y + L2 * np.sin(t2)
    leg1 = np.sign((a1x - o1x) * (y - a1y) - (a1y - o1y) * (x - a1x))
    leg2 = np.sign((a2x - o2x) * (y - a2y) - (a2y - o2y) * (x - a2x))
    design_mode = ok & (leg1 == -1) & (leg2 == +1)  # "-+"
    assert design_mode.sum() > 100
    s1, s2, st = fivebar.ik(index_lower, x[design_mode], y[design_mode])
    assert (st == int(fivebar.Status.ok)).mean() > 0.99
    wrap = lambda a: np.angle(np.exp(1j * a))
    back = st == int(fivebar.Status.ok)
    assert np.abs(wrap(s1 - t1[design_mode]))[back].max() < 1e-8
    assert np.abs(wrap(s2 - t2[design_mode]))[back].max() < 1e-8


def test_jacobian_matches_central_differences(index_lower):
    t1, t2 = np.array([1.9, 1.6, 2.2]), np.array([1.2, 1.4, 0.9])
    J, status = fivebar.jacobian(index_lower, t1, t2)
    assert J.shape == (3, 2, 2)
    h = 1e-6
    for k in range(3):
        if status[k] != int(fivebar.Status.ok):
            continue
        for j, (d1, d2) in enumerate(((h, 0.0), (0.0, h))):
            plus = fivebar.fk(index_lower, t1[k] + d1, t2[k] + d2).P
            minus = fivebar.fk(index_lower, t1[k] - d1, t2[k] - d2).P
            numeric = (np.array(plus) - np.array(minus)) / (2 * h)
            assert J[k, :, j] == pytest.approx(numeric, abs=1e-5)
    J0, s0 = fivebar.jacobian(index_lower, t1[0], t2[0])
    assert J0 == pytest.approx(J[0]) and s0 == fivebar.Status(status[0])


def test_lci_is_inverse_condition_number(index_lower):
    x, y = np.array([6.25, 5.0, 8.0]), np.array([15.5, 13.0, 17.0])
    value, status = fivebar.lci(index_lower, x, y)
    t1, t2, st = fivebar.ik(index_lower, x, y)
    J, _ = fivebar.jacobian(index_lower, t1, t2)
    for k in range(3):
        assert status[k] == int(fivebar.Status.ok)
        s = np.linalg.svd(J[k], compute_uv=False)
        assert value[k] == pytest.approx(s[1] / s[0], rel=1e-9)
    assert fivebar.lci(index_lower, 6.25, 15.5)[0] == pytest.approx(value[0])


def test_out_arrays_are_written_in_place_without_batch_sized_allocations(index_lower):
    n = 1_000_000
    t1, t2 = random_angles(n)
    x, y, st = np.empty(n), np.empty(n), np.empty(n, dtype=np.uint8)
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        rx, ry, rs = fivebar.fk(index_lower, t1, t2, out=(x, y, st))
        _, peak = tracemalloc.get_traced_memory()
        # The same calls with a strided input must copy it: the measurement does see copies.
        tracemalloc.reset_peak()
        fivebar.fk(index_lower, t1[::2], t2[::2], out=(x[: n // 2], y[: n // 2], st[: n // 2]))
        _, strided_peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert rx is x and ry is y and rs is st
    assert peak < 64 * 1024, f"{peak} bytes allocated for a batch of {n}"
    assert strided_peak >= 8 * (n // 2)
    ref = fivebar.fk(index_lower, t1[:20:2], t2[:20:2])  # the strided call wrote last
    assert x[:10] == pytest.approx(ref[0])


def test_new_outputs_are_owned_arrays(index_lower):
    t1, t2 = random_angles(10)
    x, y, st = fivebar.fk(index_lower, t1, t2)
    assert x.flags.c_contiguous and x.flags.writeable and x.flags.owndata
    t = np.stack([t1, t2])  # 2-D inputs keep their shape
    x2, _, _ = fivebar.fk(index_lower, t, t[::-1].copy())
    assert x2.shape == (2, 10)


def test_bad_input_raises_naming_the_problem(index_lower):
    t = np.zeros(4)
    with pytest.raises(TypeError, match=r"theta1: dtype float32, expected float64"):
        fivebar.fk(index_lower, t.astype(np.float32), t)
    with pytest.raises(TypeError, match=r"x: dtype int64"):
        fivebar.ik(index_lower, np.arange(4), t)
    with pytest.raises(ValueError, match=r"shape mismatch: theta1 has shape \(4,\), theta2 has \(3,\)"):
        fivebar.fk(index_lower, t, np.zeros(3))
    bad = t.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match=r"theta2 holds NaN at flat index 2"):
        fivebar.fk(index_lower, t, bad)
    bad[2] = np.inf
    with pytest.raises(ValueError, match=r"y holds an infinity at flat index 2"):
        fivebar.lci(index_lower, t, bad)
    with pytest.raises(ValueError, match="theta1 = nan: must be finite"):
        fivebar.fk(index_lower, float("nan"), 0.0)
    with pytest.raises(TypeError, match=r"out: status must be a C-contiguous numpy array of dtype uint8"):
        fivebar.fk(index_lower, t, t, out=(np.empty(4), np.empty(4), np.empty(4)))
    with pytest.raises(ValueError, match=r"out: x has shape \(5,\), the inputs \(4,\)"):
        fivebar.fk(index_lower, t, t, out=(np.empty(5), np.empty(4), np.empty(4, np.uint8)))
    readonly = np.empty(4)
    readonly.flags.writeable = False
    with pytest.raises(ValueError, match="out: y is read-only"):
        fivebar.fk(index_lower, t, t, out=(np.empty(4), readonly, np.empty(4, np.uint8)))
    with pytest.raises(fivebar.InputError, match="branch"):
        fivebar.fk(index_lower, 0.0, 0.0, branch="sideways")


def test_gil_is_released_during_a_batch(index_lower):
    """A second Python thread keeps running while the kernel works: it wakes from 1 ms sleeps
    many times during the call. Were the GIL held, it could not wake up until the call returned."""
    n = 2_000_000
    t1, t2 = random_angles(n)
    ticks = []
    running = threading.Event()
    done = threading.Event()

    def ticker():
        running.set()
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    running.wait()
    try:
        start = time.perf_counter()
        J, status = fivebar.jacobian(index_lower, t1, t2)  # the full-pose path: tenths of a second
        end = time.perf_counter()
    finally:
        done.set()
        thread.join()
    during = [t for t in ticks if start < t < end]
    assert end - start > 0.05, "the batch was too short to tell"
    assert len(during) >= 10, f"{len(during)} ticks in {end - start:.3f} s"


def test_units_are_explicit(index_lower):
    """Degrees only with unit="deg"; without unit= an angle beyond one turn is refused, so
    fk(m, 100, 80) cannot mean 100 rad silently. unit="deg" equals the radians given by hand."""
    with pytest.raises(fivebar.InputError, match=r"theta1 = 100: .*unit='deg'"):
        fivebar.fk(index_lower, 100, 80)
    with pytest.raises(fivebar.InputError, match=r"theta2 = 80"):
        fivebar.fk(index_lower, np.array([0.5, 1.0]), np.array([1.0, 80.0]))
    with pytest.raises(fivebar.InputError, match=r"theta1"):
        fivebar.jacobian(index_lower, 100.0, 80.0)
    with pytest.raises(ValueError, match=r"unit = 'grad'"):
        fivebar.fk(index_lower, 1.0, 1.0, unit="grad")
    deg = fivebar.fk(index_lower, 100, 80, unit="deg")
    rad = fivebar.fk(index_lower, math.radians(100), math.radians(80))
    assert deg.status == rad.status and deg.P == pytest.approx(rad.P, abs=0.0)
    # Radians beyond one turn when the caller says so: the same point as the angle less 2 pi.
    far = fivebar.fk(index_lower, math.radians(100) + 2 * math.pi, math.radians(80), unit="rad")
    assert far.P == pytest.approx(rad.P, abs=1e-12)
    t = np.array([100.0, 95.0])
    xd, yd, sd = fivebar.fk(index_lower, t, t[::-1].copy(), unit="deg")
    xr, yr, sr = fivebar.fk(index_lower, np.deg2rad(t), np.deg2rad(t[::-1]))
    assert np.array_equal(xd, xr) and np.array_equal(yd, yr) and np.array_equal(sd, sr)
    Jd, _ = fivebar.jacobian(index_lower, 100, 80, unit="deg")
    Jr, _ = fivebar.jacobian(index_lower, math.radians(100), math.radians(80))
    assert np.array_equal(Jd, Jr)


def test_arrays_broadcast_as_numpy_does(index_lower):
    """A row of x with a column of y is a grid; each cell equals the scalar call at that point.
    A scalar with an array is the array of that scalar. Shapes that do not broadcast are refused."""
    xs = np.linspace(0.0, 12.5, 7)
    ys = np.linspace(14.0, 18.0, 5)
    t1, t2, st = fivebar.ik(index_lower, xs[None, :], ys[:, None])
    assert t1.shape == t2.shape == st.shape == (5, 7)
    for j, y in enumerate(ys):
        for i, x in enumerate(xs):
            pose = fivebar.ik(index_lower, float(x), float(y))
            assert int(st[j, i]) == int(pose.status)
            if pose.status == fivebar.Status.ok:
                assert (t1[j, i], t2[j, i]) == pytest.approx((pose.theta1, pose.theta2), abs=1e-12)
    lg, _ = fivebar.lci(index_lower, xs[None, :], ys[:, None])
    assert lg[2, 3] == pytest.approx(fivebar.lci(index_lower, float(xs[3]), float(ys[2]))[0], abs=1e-15)
    a = np.linspace(0.5, 2.5, 9)
    x1, y1, s1 = fivebar.fk(index_lower, 1.6, a)
    x2, y2, s2 = fivebar.fk(index_lower, np.full_like(a, 1.6), a)
    assert np.array_equal(x1, x2) and np.array_equal(y1, y2) and np.array_equal(s1, s2)
    J, _ = fivebar.jacobian(index_lower, a[:, None], a[None, :])
    assert J.shape == (9, 9, 2, 2)
    with pytest.raises(ValueError, match=r"shape mismatch: x has shape \(7,\), y has \(5,\), which do not broadcast"):
        fivebar.ik(index_lower, xs, ys)
