"""The observer's sigma widened by the dry-friction band (:mod:`alpes_dyn.estimation.observers.band_sigma`): (B1)
against independent references (the static stiffness against Pinocchio's gravity derivatives with the springs, the
split's covariance against a Monte Carlo regression), bad input named, and on MuJoCo's stick-slip finger3
``estimate --data --band-sigma`` bringing the joints' NEES from above their band into it, the estimate and the
unobserved flag unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers import band_sigma as bs
from alpes_dyn.model.robot import Model


@pytest.fixture(scope="module")
def finger3():
    return Model.alpes("finger3", friction=True)


def test_the_static_stiffness_is_the_springs_and_gravitys(finger3):
    """K of (B1) at rest: Pinocchio's gravity derivatives plus the springs (Model.gravity_jacobian, eq. 2.11) on
    finger3's constant ratios; H its encoder's ratios."""
    q = np.array([0.3, 0.5, 0.2])
    K, H = (np.asarray(a) for a in bs._static_terms(finger3)(q, [0.01]))
    np.testing.assert_allclose(K, finger3.gravity_jacobian(q), rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(H, finger3.transmission.S, rtol=1e-12)


def test_the_split_is_the_regression_residual_of_a_monte_carlo(finger3):
    """(B1) against its definition: friction torques drawn N(0, (c F_s)^2), the joints K^-1 f, the part the encoder
    explains regressed out; the residuals' variances match C_split's diagonal within the draw's error."""
    q = np.array([0.3, 0.5, 0.2])
    N = 4
    out = bs.band_sigma(finger3, np.tile(q, (N, 1)), np.full((N - 1, 1), 0.01), fraction=0.4)
    K, H = (np.asarray(a) for a in bs._static_terms(finger3)(q, [0.01]))
    rng = np.random.default_rng(1)
    f = rng.normal(size=(200_000, 3)) * 0.4 * np.asarray(finger3.extras.coulomb)
    dq = np.linalg.solve(K, f.T).T
    y = dq @ H.T
    beta = np.linalg.lstsq(y, dq, rcond=None)[0]
    np.testing.assert_allclose(out.variance, np.broadcast_to((dq - y @ beta).var(axis=0), (N, 3)), rtol=0.02)
    assert out.unbounded == () and out.fraction == 0.4
    assert (np.linalg.norm(H @ np.linalg.solve(K, np.diag(np.sqrt(out.variance[0])))) > 0)


def test_the_widened_estimate_adds_to_the_joints_alone(finger3):
    from alpes_dyn.estimation.observers.observers import Estimate

    P = np.broadcast_to(np.diag([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]), (2, 6, 6)).copy()
    est = Estimate(t=np.arange(2.0), z=np.zeros((2, 6)), P=P, names=tuple("abcdef"))
    band = bs.BandSigma(0.3, np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]))
    w = band.widened(est)
    np.testing.assert_allclose(np.diagonal(w.P, axis1=1, axis2=2)[:, :3], [[1.1, 2.2, 3.3], [1.4, 2.5, 3.6]])
    np.testing.assert_allclose(np.diagonal(w.P, axis1=1, axis2=2)[:, 3:], [[4, 5, 6]] * 2)
    assert w.z is est.z and np.array_equal(est.P, P)
    np.testing.assert_allclose(band.to_dict(1)["band_rms_deg"], np.degrees(np.sqrt([0.4, 0.5, 0.6])))


@pytest.mark.parametrize("kwargs, field", [({"fraction": -0.1}, "fraction"), ({"fraction": float("nan")}, "fraction"),
                                           ({"fraction": True}, "fraction"), ({"states": np.zeros((5, 2))}, "states"),
                                           ({"inputs": np.zeros((5, 1))}, "inputs"), ({"model": "finger3"}, "model"),
                                           ({"law": "viscous"}, "law")])
def test_bad_input_is_named(finger3, kwargs, field):
    args = {"model": finger3, "states": np.zeros((5, 6)), "inputs": np.zeros((4, 1))} | kwargs
    with pytest.raises(InputError, match=field):
        bs.band_sigma(**args)


def test_on_a_stick_slip_plant_estimate_band_sigma_brings_the_nees_into_its_band(tmp_path, capsys):
    """finger3 in MuJoCo with stick-slip (the stiff constraint), the estimate scenario's torque then the ramp (6 s),
    ``estimate --data --band-sigma`` on the plant's true file with the smooth law: each joint's NEES with the
    filter's own sigma (the log's q_std with ``--no-band-sigma``; every 0.1 s after 1 s) is above its band;
    widened by the band (the JSON's, same samples) most joints are in their band and none is off by more than a
    factor of three, the log's q_std the sigma reported (its NEES the JSON's), the estimate (its log) the filter's,
    the same with and without the band, no joint flagged unobserved (the flag reads the estimate, which the widening
    leaves as it is: ``test_the_widened_estimate_adds_to_the_joints_alone``), the band's term in the JSON."""
    import json

    from alpes_dyn.bench.effects import PlantEffects
    from alpes_dyn.bench.truth import write_truth
    from alpes_dyn.cli import main
    from alpes_dyn.control.plants import mujoco_recording
    from alpes_dyn.estimation.experiments.recording import write_recording
    from alpes_dyn.estimation.observers.consistency import chi2_band
    from alpes_dyn.model.mjcf import STICTION_TIMECONST
    from alpes_dyn.model.params import load_params
    from alpes_dyn.studies.realism_friction import validation_torque

    e = PlantEffects(stiction=STICTION_TIMECONST)
    true = load_params()
    rec = mujoco_recording("finger3", true, validation_torque(1e-3)[:6001], 1e-3, effects=e, seed=5)
    t = write_truth(true, e, tmp_path / "truth.toml")
    write_recording(rec, tmp_path / "rec.csv")
    base = ["estimate", "--data", str(tmp_path / "rec.csv"), "--params", str(t.path), "--friction", "--stops",
            "--friction-law", "smooth", "--json"]
    assert main(base + ["--band-sigma", "--log", str(tmp_path / "log.csv")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert main(base + ["--no-band-sigma", "--log", str(tmp_path / "own.csv")]) == 0
    capsys.readouterr()
    log, own_log = (np.genfromtxt(tmp_path / f, delimiter=",", names=True) for f in ("log.csv", "own.csv"))
    names = ("j1", "j2", "j3")
    k = np.arange(1000, rec.true_q.shape[0], 100)
    assert out["nees"]["samples"] == k.size
    q_hat = np.column_stack([log[f"q_hat_{j}"] for j in names])
    np.testing.assert_allclose(q_hat, np.column_stack([own_log[f"q_hat_{j}"] for j in names]), atol=1e-12)

    def nees_of(lg):
        std = np.column_stack([lg[f"q_std_{j}"] for j in names])
        return np.mean(((q_hat[k] - rec.true_q[k]) / std[k]) ** 2, axis=0)

    own = nees_of(own_log)
    lo, hi = chi2_band(1, k.size, 0.95)
    assert (own > hi).all(), own
    widened = np.array(out["nees"]["per_joint"])
    np.testing.assert_allclose(nees_of(log), widened, rtol=1e-3)  # the log holds the sigma reported
    assert ((widened >= lo) & (widened <= hi)).sum() >= 2 and ((widened > 1 / 3) & (widened < 3)).all(), widened
    rmse = np.sqrt(np.mean((q_hat[1000:] - rec.true_q[1000:]) ** 2, axis=0))
    np.testing.assert_allclose(out["rmse"], rmse, rtol=1e-6)
    assert out["unobserved"] == [] and out["band_sigma"]["fraction"] == bs.BAND_FRACTION
    own_std = np.column_stack([own_log[f"q_std_{j}"] for j in names])
    assert (np.array(out["q_sigma_deg"]) > np.degrees(own_std[1000:].max(axis=0))).all()


def test_a_direction_the_band_does_not_bound_is_the_prior():
    """(B1) on small systems by hand: two joints on one encoder, springs 1 and 2 N m/rad, the split direction
    (1, -1) of information 1/0.1^2 + 4/0.05^2 over 2; two springless joints with friction: that direction unbounded,
    each joint at UNBOUNDED_STD (the prior's 0.5 rad shared along it: half its variance each) and named; a
    springless joint alone on its encoder: seen, 0; a springless joint without friction beside a sprung one: held
    through the tendon by the other's band."""
    H = np.ones((1, 1, 2))
    out = bs._split(np.diag([1.0, 2.0])[None], H, np.array([0.1, 0.05]), 0.5, ("a", "b"))
    info = (1 / 0.1**2 + 4 / 0.05**2) / 2  # along (1, -1) / sqrt(2)
    np.testing.assert_allclose(out.variance[0], [0.5 / info, 0.5 / info], rtol=1e-9)
    assert out.unbounded == ()
    out = bs._split(np.zeros((1, 2, 2)), H, np.array([0.1, 0.05]), 0.5, ("a", "b"))
    np.testing.assert_allclose(out.variance[0], [0.5 * bs.UNBOUNDED_STD ** 2] * 2, rtol=1e-9)
    assert out.unbounded == ("a", "b")
    out = bs._split(np.zeros((1, 1, 1)), np.ones((1, 1, 1)), np.array([0.1]), 0.5, ("a",))
    np.testing.assert_allclose(out.variance, [[0.0]], atol=1e-15)
    out = bs._split(np.diag([1.0, 0.0])[None], H, np.array([0.1, 0.0]), 0.5, ("a", "b"))
    np.testing.assert_allclose(out.variance[0], [0.5 * 0.1**2 * 2, 0.5 * 0.1**2 * 2], rtol=1e-9)
    assert out.unbounded == ()


def test_the_hand_s_springless_thumb_abduction_seen_by_its_own_encoder_is_bounded():
    """The hand: thumb_abd has no spring but its own motor, so its encoder sees it whole: no joint unbounded, the
    abduction's band 0, each finger's joints as the lone finger3's at the same angles."""
    hand = Model.alpes("hand", friction=True)
    q = np.tile(np.full(hand.n, 0.3), (3, 1))
    out = bs.band_sigma(hand, q, np.zeros((2, hand.transmission.n_motors)))
    assert out.unbounded == ()
    np.testing.assert_allclose(out.variance[:, hand.joint_names.index("thumb_abd")], 0.0, atol=1e-15)
    f3 = bs.band_sigma(Model.alpes("finger3", friction=True), np.full((3, 3), 0.3), np.zeros((2, 1)))
    idx = [hand.joint_names.index(f"index_{j}") for j in ("j1", "j2", "j3")]
    np.testing.assert_allclose(out.variance[:, idx], f3.variance, rtol=1e-6)


def test_each_library_law_has_its_fraction_and_an_unknown_law_is_named():
    """band_fraction: c for every law of the library (the smooth law's the default's, the stick-slip law's smaller:
    it holds a stuck joint where the plant does), an unknown law refused naming ``law``."""
    from alpes_dyn.simulation.stick import LIBRARY_LAWS

    assert set(bs.BAND_FRACTIONS) == set(LIBRARY_LAWS)
    assert bs.band_fraction("smooth") == bs.BAND_FRACTION
    assert 0 < bs.band_fraction("stick") < bs.band_fraction("smooth") < 1 / np.sqrt(3)
    for bad in ("dahl", None, 3):
        with pytest.raises(InputError, match="law: expected one of smooth, stick, lugre, creep"):
            bs.band_fraction(bad)
