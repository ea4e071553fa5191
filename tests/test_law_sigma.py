"""The observer's sigma widened by the spread between the friction laws (:mod:`alpes_dyn.estimation.observers.
law_sigma`): (L1) against its sum written out, bad input named, and on MuJoCo's stick-slip finger3 with the true
file the joints' NEES brought from over-confident to near its band."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.law_sigma import law_sigma
from alpes_dyn.estimation.observers.observers import Estimate


def _fake(law, q):
    return SimpleNamespace(settings={"friction_law": law}, q_hat=q)


def test_the_spread_is_the_other_laws_squared_differences():
    """Four laws' joints given: the spread is w^2 times the mean of the three others' squared differences from the
    kept one, and the widened estimate's joint variances are P's plus it (the velocities' untouched)."""
    rng = np.random.default_rng(0)
    q = {law: rng.normal(size=(5, 2)) for law in ("smooth", "stick", "lugre", "creep")}
    seen = []

    def run(law):
        seen.append(law)
        return _fake(law, q[law])

    s = law_sigma(run, _fake("stick", q["stick"]), weight=2.0)
    assert s.kept == "stick" and s.others == ("smooth", "lugre", "creep") and seen == ["smooth", "lugre", "creep"]
    expect = 4.0 / 3.0 * sum((q[law] - q["stick"]) ** 2 for law in ("smooth", "lugre", "creep"))
    np.testing.assert_allclose(s.spread, expect, rtol=1e-12)
    P = np.broadcast_to(np.diag([1.0, 2.0, 3.0, 4.0]), (5, 4, 4)).copy()
    w = s.widened(Estimate(t=np.arange(5.0), z=np.zeros((5, 4)), P=P, names=("a", "b", "c", "d")))
    np.testing.assert_allclose(np.diagonal(w.P, axis1=1, axis2=2), np.column_stack([1 + expect[:, 0],
                               2 + expect[:, 1], np.full(5, 3.0), np.full(5, 4.0)]), rtol=1e-12)
    np.testing.assert_allclose(s.to_dict()["spread_rms_deg"], np.degrees(np.sqrt(expect.mean(axis=0))), rtol=1e-12)


@pytest.mark.parametrize("kwargs, field", [({"weight": -1.0}, "weight"), ({"weight": float("nan")}, "weight"),
                                           ({"weight": True}, "weight"), ({"laws": ("smooth", "coulomb")}, "laws"),
                                           ({"kept_law": "tanh"}, "kept_law")])
def test_bad_input_is_named(kwargs, field):
    with pytest.raises(InputError, match=field):
        law_sigma(lambda law: _fake(law, np.zeros((3, 2))), _fake("smooth", np.zeros((3, 2))), **kwargs)


def test_a_run_of_another_shape_is_named():
    with pytest.raises(InputError, match="run"):
        law_sigma(lambda law: _fake(law, np.zeros((4, 2))), _fake("smooth", np.zeros((3, 2))))


def test_on_a_stick_slip_plant_estimate_law_spread_widens_sigma_to_cover_the_true_files_error(tmp_path, capsys):
    """finger3 in MuJoCo with stick-slip (the stiff constraint), the estimate scenario's torque then the ramp
    (6 s), ``estimate --data --law-spread`` on the plant's true file with the smooth law: the filter's own sigma (its
    log's q_std) is over-confident (a joint's NEES, computed here from the log every 0.1 s after 1 s, above 3); each
    joint's variance widened by the spread to the stick-slip and LuGre laws' estimates, every joint's NEES is within
    a factor two of 1 (the friction study's per-joint band at 100 samples is 0.74-1.29), its sigma above the
    filter's own, the spread in its JSON (the band of ``estimate``'s default left out: --no-band-sigma)."""
    import json

    from alpes_dyn.bench.effects import PlantEffects
    from alpes_dyn.bench.truth import write_truth
    from alpes_dyn.cli import main
    from alpes_dyn.control.plants import mujoco_recording
    from alpes_dyn.estimation.experiments.recording import write_recording
    from alpes_dyn.model.mjcf import STICTION_TIMECONST
    from alpes_dyn.model.params import load_params
    from alpes_dyn.studies.realism_friction import validation_torque

    e = PlantEffects(stiction=STICTION_TIMECONST)
    true = load_params()
    rec = mujoco_recording("finger3", true, validation_torque(1e-3)[:6001], 1e-3, effects=e, seed=5)
    t = write_truth(true, e, tmp_path / "truth.toml")
    write_recording(rec, tmp_path / "rec.csv")
    assert main(["estimate", "--data", str(tmp_path / "rec.csv"), "--params", str(t.path), "--friction", "--stops",
                 "--friction-law", "smooth", "--law-spread", "--no-band-sigma", "--log", str(tmp_path / "log.csv"),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    log = np.genfromtxt(tmp_path / "log.csv", delimiter=",", names=True)
    k = np.arange(1000, rec.true_q.shape[0], 100)
    names = ("j1", "j2", "j3")
    err = np.column_stack([log[f"q_hat_{j}"][k] for j in names]) - rec.true_q[k]
    std = np.column_stack([log[f"q_std_{j}"][k] for j in names])
    own = np.mean((err / std) ** 2, axis=0)
    assert own.max() > 3.0, own
    widened = np.array(out["nees"]["per_joint"])
    assert ((widened > 0.5) & (widened < 2.0)).all(), (own, widened)
    assert out["law_spread"]["kept"] == "smooth" and out["law_spread"]["others"] == ["stick", "lugre", "creep"]
    own_worst = np.degrees([log[f"q_std_{j}"][1000:].max() for j in names])
    assert (np.array(out["q_std_worst_deg"]) > own_worst).all()


def test_the_library_laws_on_a_file():
    """law_model: each law of the library on the same file with its friction.law (no refit: every other value the
    file's), the observer's law to run it with; library_law names a creep file's smooth-law run creep."""
    from alpes_dyn.model.params import Param, load_params, with_values
    from alpes_dyn.model.robot import Model
    from alpes_dyn.simulation.stick import LIBRARY_LAWS, law_model, library_law

    creep = Model.alpes("finger3", friction=True, params=with_values(
        load_params(), {"friction.law": Param("creep", "-", "assumed", "test")}))
    assert library_law(creep, "smooth") == "creep" and library_law(creep, "stick") == "stick"
    for law, (observer, file_law) in LIBRARY_LAWS.items():
        m, obs = law_model(creep, law)
        assert obs == observer and m.params.friction_law == file_law
        assert library_law(m, obs) == law
        assert (m is creep) == (file_law == "creep")
        np.testing.assert_allclose(m.extras.coulomb, creep.extras.coulomb, rtol=1e-12)
        raw, mine = m.params.raw, creep.params.raw
        assert {k for k in set(raw) | set(mine) if repr(raw.get(k)) != repr(mine.get(k))} <= {"friction.law"}
    lugre = Model.alpes("finger3", friction=True, params=with_values(
        load_params(), {"friction.law": Param("lugre", "-", "assumed", "test")}))
    assert library_law(lugre, "lugre") == "lugre" and law_model(lugre, "lugre")[0] is lugre
    assert [law_model(lugre, law)[0].params.friction_law for law in ("smooth", "stick", "creep")] == \
        ["tanh", "tanh", "creep"]
    tanh = Model.alpes("finger3", friction=True)
    assert library_law(tanh, "smooth") == "smooth" and law_model(tanh, "smooth")[0] is tanh
    with pytest.raises(InputError, match="law"):
        law_model(tanh, "tanh")


def test_estimate_law_spread_on_a_creep_file_keeps_creep_and_runs_the_smooth_law(tmp_path, capsys):
    """A creep file (friction.law = "creep") on 1.5 s of MuJoCo's soft dry friction (finger3, the plant the law
    models): ``estimate --data --law-spread`` names the kept law creep and runs the plain smooth law (the same file
    with friction.law = "tanh": its joints, run here without --law-spread, are a third of what the spread counts),
    stick-slip and LuGre; the spread is > 0 and each joint's worst sigma at least the filter's own (its log's q_std)."""
    import json

    from alpes_dyn.bench.effects import PlantEffects
    from alpes_dyn.cli import main
    from alpes_dyn.control.plants import mujoco_recording
    from alpes_dyn.estimation.experiments.recording import write_recording
    from alpes_dyn.model.params import Param, load_params, with_values, write_params
    from alpes_dyn.studies.realism_friction import validation_torque

    true = load_params()
    rec = mujoco_recording("finger3", true, validation_torque(1e-3, 1)[:1501], 1e-3,
                           effects=PlantEffects(soft_stiction=True), seed=3)
    write_recording(rec, tmp_path / "rec.csv")
    files = {law: str(write_params(with_values(true, {"friction.law": Param(law, "-", "assumed", "test")}),
                                   tmp_path / f"{law}.toml")) for law in ("creep", "tanh")}

    def estimate(law, *more):
        assert main(["estimate", "--data", str(tmp_path / "rec.csv"), "--params", files[law], "--friction",
                     "--log", str(tmp_path / f"{law}.csv"), "--json", *more]) == 0
        return json.loads(capsys.readouterr().out), np.genfromtxt(tmp_path / f"{law}.csv", delimiter=",",
                                                                   names=True)

    out, log = estimate("creep", "--law-spread")
    assert out["law_spread"]["kept"] == "creep" and out["law_spread"]["others"] == ["smooth", "stick", "lugre"]
    spread = np.array(out["law_spread"]["spread_rms_deg"])
    _, smooth = estimate("tanh")
    names = ("j1", "j2", "j3")
    k0 = 300  # the transient counted out (0.2 of the run)
    d2 = np.mean([(smooth[f"q_hat_{j}"][k0:] - log[f"q_hat_{j}"][k0:]) ** 2 for j in names], axis=1)
    # the smooth law's share of the mean over the three others (each other law's share >= 0)
    assert (spread > 0).all() and (spread >= np.degrees(np.sqrt(d2 / 3)) * (1 - 1e-6)).all(), (spread, d2)
    own_worst = np.degrees([log[f"q_std_{j}"][k0:].max() for j in names])
    assert (np.array(out["q_std_worst_deg"]) >= own_worst * (1 - 1e-9)).all()
