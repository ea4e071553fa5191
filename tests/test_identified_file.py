"""Every identified quantity in the file, and the file's trust (issue 49, item 5).

A recording of the MuJoCo finger3 with a palm tilted by 3 degrees, its torque read 1 sample late and its encoder 40
counts off: ``identify --effects tilt,delay,offset -o`` writes the tilt (as the gravity it turns), the delay and the
encoder's zero, each ``identified``; every reader takes them back (the model's gravity, ``estimate --data``'s
observer, ``control``'s compensation, ``codegen``'s note to the C's caller). References: the fit's own values
(``--json``), :func:`~alpes_dyn.symbolic.parametric.tilted_gravity` on the shipped gravity, the MuJoCo plant's
tilt and delay. A file written by ``identify --force`` is refused by estimate, codegen and control with its reason,
and runs with ``--force``, the output saying it is not trustworthy.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.errors import ModelError
from alpes_dyn.model.params import Param, load_params, with_values, write_params
from alpes_dyn.model.trust import check_trusted
from alpes_dyn.symbolic.parametric import tilted_gravity

TILT_DEG, DELAY, OFFSET_COUNTS = 3.0, 1, 40.0  # an encoder zero the 2 s recording tells from none (4 std errors)


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """(the recording's path, the identified file's path, identify's JSON)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment_torque
    from alpes_dyn.estimation.experiments.recording import write_recording

    d = tmp_path_factory.mktemp("ident")
    p = load_params()
    design = ExperimentDesign(duration=2.0)
    _, u, x0 = experiment_torque("finger3", p, design)
    rec = mujoco_recording("finger3", p, u, design.dt, seed=4, q0=x0[:3],
                           effects=PlantEffects(tilt=math.radians(TILT_DEG), torque_delay=DELAY,
                                                encoder_offset=OFFSET_COUNTS))
    path = write_recording(rec, d / "rec.csv")
    out = d / "ident.toml"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["identify", "--data", str(path), "--effects", "tilt,delay,offset", "-o", str(out), "--json"])
    assert code == 0
    return str(path), str(out), json.loads(buf.getvalue())


def test_the_file_holds_the_tilt_the_delay_and_the_zero_the_fit_found(fitted):
    """Read back: the gravity is the shipped one turned by the fitted tilt_y (to 1e-12), the delay the fit's
    (1 sample, the plant's), the encoder's zero the fit's value and standard error, each marked identified; the
    model built from the file has that gravity. The fitted tilt is the plant's 3 degrees (the fit's sign: tilt_y =
    -tilt) within 3 standard errors."""
    _, path, obj = fitted
    pars = obj["parameters"]
    p = load_params(path)
    ty = pars["tilt_y"]["value"]
    assert ty == pytest.approx(-math.radians(TILT_DEG), abs=3 * pars["tilt_y"]["std"])
    g = np.asarray(tilted_gravity(np.asarray(load_params().gravity), pars.get("tilt_x", {"value": 0.0})["value"], ty))
    np.testing.assert_allclose(p.gravity, g, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ad.Model.alpes("finger3", params=path).gravity, g, rtol=0, atol=1e-12)
    assert p.raw["environment.gravity"].source == "identified" and "tilt_y" in p.raw["environment.gravity"].reason
    std = np.asarray(p.raw["environment.gravity"].std)
    assert std[0] == pytest.approx(9.81 * math.cos(ty) * pars["tilt_y"]["std"], rel=0.01)  # |dg_x/dtilt_y| sd
    assert obj["torque_delay"] == DELAY and p.torque_delay == DELAY
    assert p.raw["transmission.torque_delay"].source == "identified"
    off = pars["encoder_offset_finger"]
    assert p.finger.encoder_offset == pytest.approx(off["value"], rel=1e-12)
    assert p.raw["finger.encoder_offset"].std == pytest.approx(off["std"], rel=1e-12)
    assert p.raw["finger.encoder_offset"].source == "identified"


def test_estimate_reads_them_back(fitted, capsys, cli_text):
    """``estimate --data`` on the identified file runs with its delay and zero (the same numbers as given on the
    command line), and says they came from the file."""
    rec, path, obj = fitted
    off = obj["parameters"]["encoder_offset_finger"]["value"]
    assert main(["estimate", "--data", rec, "--params", path, "--friction", "--json"]) == 0
    auto = json.loads(capsys.readouterr().out)
    assert auto["torque_delay_samples"] == DELAY
    assert auto["encoder_offset_rad"] == pytest.approx([off], rel=1e-12)
    assert main(["estimate", "--data", rec, "--params", path, "--friction", "--json", "--torque-delay", str(DELAY),
                 "--encoder-offset", repr(off)]) == 0
    given = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(auto["rmse"], given["rmse"], rtol=1e-9)
    assert f"from --params: torque delay {DELAY} samples; encoder offset" in cli_text[0]  # the first run's table
    # without them (as before the file held them): the joints 3.4 times further off on the worst (1.29 against 0.38
    # degrees when measured)
    assert main(["estimate", "--data", rec, "--params", path, "--friction", "--json", "--torque-delay", "0",
                 "--encoder-offset", "0"]) == 0
    blind = json.loads(capsys.readouterr().out)
    assert max(auto["rmse"]) < 0.5 * max(blind["rmse"])


def test_control_and_codegen_read_them_back(fitted, tmp_path, capsys):
    """control: the compensation's encoder zero is the file's (Compensation.encoder_offset None); codegen tells the
    C's caller the zero and the delay (its JSON too)."""
    from alpes_dyn.control.realism_loop import Compensation

    _, path, obj = fitted
    p = load_params(path)
    assert Compensation().offset_of(p, "finger") == pytest.approx(obj["parameters"]["encoder_offset_finger"]["value"])
    assert Compensation(encoder_offset=0.001).offset_of(p, "finger") == 0.001
    assert main(["codegen", "--params", path, "--out-dir", str(tmp_path / "c"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["torque_delay_samples"] == DELAY and out["encoder_offset_rad"] == pytest.approx([p.finger.encoder_offset])
    assert "Subtract the identified encoder zero" in (tmp_path / "c" / "alpes_ekf.h").read_text()


def test_a_fit_without_the_zero_takes_the_old_one_out():
    """identified_params on a file with an identified encoder zero, from a fit that fitted none: the zero is taken
    out (the fit assumed none); the delay the fit did not try stays (the rig's)."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification.fit_result import identified_params

    base = with_values(load_params(), {
        "finger.encoder_offset": Param(0.01, "rad", "identified", "earlier"),
        "transmission.torque_delay": Param(2, "samples", "identified", "earlier")})
    model = ad.Model.alpes("finger3", params=base)
    res = SimpleNamespace(model=model, names=("K_1",), values=np.array([0.041]), std=np.array([1e-4]),
                          not_identified={}, recording_path="r.csv", residual_rms=0.5, trustworthy=True,
                          converged=True, reason="", adequacy=None, torque_delay=None,
                          correlation=np.eye(1), status=lambda: "converged", standard_errors=None,
                          model_error=None)
    p = identified_params(res, base)
    assert "finger.encoder_offset" not in p.raw and p.finger.encoder_offset == 0.0
    assert p.torque_delay == 2 and p.finger.K[0] == pytest.approx(0.041)
    # a zero and a tilt the recording cannot tell from none (95 % interval past 0) are not written either
    weak = SimpleNamespace(**{**vars(res), "names": ("K_1", "encoder_offset_finger", "tilt_y"),
                              "values": np.array([0.041, 0.01, 0.02]), "std": np.array([1e-4, 0.01, 0.011]),
                              "correlation": np.eye(3)})
    q = identified_params(weak, base)
    assert "finger.encoder_offset" not in q.raw and q.raw["environment.gravity"].source != "identified"
    strong = SimpleNamespace(**{**vars(weak), "std": np.array([1e-4, 0.004, 0.009])})
    q = identified_params(strong, base)
    assert q.finger.encoder_offset == pytest.approx(0.01) and q.raw["environment.gravity"].source == "identified"


@pytest.fixture()
def untrusted(tmp_path):
    p = with_values(load_params(), {}, identification={"finger": {
        "trustworthy": False, "converged": True, "adequate": False, "stop": "converged",
        "verdict": "NOT adequate: the residual follows the torque's rate (a torque delay)"}})
    return str(write_params(p, tmp_path / "untrusted.toml"))


@pytest.mark.parametrize("argv", [
    ["estimate", "--duration", "0.3"],
    ["codegen", "--out-dir", "{tmp}/c"],
    ["control", "--duration", "0.6"],
], ids=["estimate", "codegen", "control"])
def test_every_consumer_refuses_an_untrusted_file_unless_forced(argv, untrusted, tmp_path, capsys):
    """Exit 2 and one line with the file's reason; with --force it runs and its output says NOT trustworthy (the
    text's WARNING line, the JSON's not_trustworthy)."""
    if argv[0] == "control":
        pytest.importorskip("mujoco")
    argv = [a.format(tmp=tmp_path) for a in argv] + ["--params", untrusted]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert (f"--params: {untrusted!r} is marked not trustworthy (finger: NOT adequate: the residual follows the "
            "torque's rate (a torque delay)); --force uses it anyway") in err
    if argv[0] == "codegen":
        argv[2] = str(tmp_path / "c2")
    assert main(argv + ["--force", "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["not_trustworthy"] == [f"--params: {untrusted!r} is NOT trustworthy (finger: NOT adequate: the "
                                      "residual follows the torque's rate (a torque delay))"]
    if argv[0] == "codegen":
        argv[2] = str(tmp_path / "c3")
    assert main(argv + ["--force"]) == 0
    assert "WARNING: --params:" in capsys.readouterr().out


def test_the_api_refuses_unless_forced(untrusted):
    """check_trusted: the one line, or with force the note; a trusted file: nothing; the loaders of the commands
    (run_control, scenario_filter, block_controller, estimate_recording) take force=True."""
    from alpes_dyn.control.cexport import block_controller
    from alpes_dyn.estimation.cexport.cexport import scenario_filter

    p = load_params(untrusted)
    with pytest.raises(ModelError, match=r"params: .* is marked not trustworthy \(finger: NOT adequate"):
        check_trusted(p)
    assert check_trusted(p, force=True).startswith(f"{untrusted!r} is NOT trustworthy (finger: NOT adequate")
    assert check_trusted(load_params()) == ""
    for build in (lambda f: scenario_filter(params=untrusted, force=f), lambda f: block_controller(params=untrusted,
                                                                                                   force=f)):
        with pytest.raises(ModelError, match="is marked not trustworthy"):
            build(False)
        assert build(True) is not None


def test_the_file_says_the_fit_had_friction_and_estimate_reads_it(fitted, capsys):
    """identify records ``friction = true`` (its Alpes models fit with friction); ``estimate --data`` on the file
    without --friction runs the observer with friction: the same estimate as with --friction given (to 1e-12), and
    another than --no-friction's (which warns, one line, that it overrides the file)."""
    rec, path, _ = fitted
    assert load_params(path).identification["finger"]["friction"] is True
    from alpes_dyn.model.trust import fitted_friction

    assert fitted_friction(load_params(path), "index") is True  # a finger of the hand takes the shared record
    runs = {}
    for flag in ((), ("--friction",), ("--no-friction",)):
        assert main(["estimate", "--data", rec, "--params", path, "--json", *flag]) == 0
        out, err = capsys.readouterr()
        runs[flag] = (json.loads(out), err)
    (same, e0), (given, e1), (off, e2) = runs[()], runs[("--friction",)], runs[("--no-friction",)]
    assert e0 == e1 == ""
    np.testing.assert_allclose(same["rmse_deg"], given["rmse_deg"], rtol=1e-12, atol=0)
    assert not np.allclose(same["rmse_deg"], off["rmse_deg"], rtol=1e-6, atol=0)
    assert e2.count("\n") == 1 and f"--no-friction overrides --params {path}, whose fit had friction" in e2
