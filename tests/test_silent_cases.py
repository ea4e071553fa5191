"""Issue 52's bad inputs that passed silently, beside the bad-input tables (tests/test_bad_input.py): the fit's size
guard, what a fit not fitted again says of its parameters, and the URDF beside ``identify -o`` named when replaced."""

from __future__ import annotations

import argparse
import math
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import AlpesDynWarning, InputError
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment
from alpes_dyn.estimation.identification import bounds
from alpes_dyn.estimation.identification.long_record import check_fit_size, fit_bytes


@pytest.fixture(scope="module")
def short():
    """0.2 s of finger2's documented experiment (201 samples)."""
    return experiment("finger2", design=ExperimentDesign(duration=0.2))


def test_identify_refuses_a_recording_too_large_to_fit(short, monkeypatch):
    """identify sizes its fit's arrays before making any (estimate's guard: check_bytes, $ALPES_DYN_MAX_BYTES):
    over the limit, one line naming the recording and the samples; the estimate is the per-sample count of
    fit_bytes, linear in the samples (a 10-million-row finger2 recording: over 2 GiB, refused)."""
    model = ad.Model.alpes("finger2", friction=True)
    lines = ExperimentDesign().lines
    per_sample = fit_bytes(1, 4, 1, 8, 2 * len(lines) + 1)
    assert per_sample == 16.0 * ((2 * len(lines) + 1) + (4 + 8 + 2 * len(lines) + 1) + 4)
    assert fit_bytes(10_000_000, 4, 1, 8, 2 * len(lines) + 1) > 2 * 1024**3
    check_fit_size(short, model, "K,m,friction", lines)  # 201 samples: far below 2 GiB
    monkeypatch.setenv("ALPES_DYN_MAX_BYTES", str(int(100 * per_sample)))
    with pytest.raises(InputError, match=r"^recording: 201 samples for the fit would take about") as exc:
        ad.estimation.identify(model, short, "K,m,friction", excitation=lines)
    assert "\n" not in str(exc.value)


def test_a_fit_not_fitted_again_does_not_say_its_parameters_were_held():
    """The verdict's clause of a parameter the data do not support says where it was held only where a fit again
    held it; a fit not to be trusted (written only with --force) is not fitted again, and its clause says so."""
    args = (("K_1", "m_1"), ("K", "m"), (0.04, 1e-9), (1e-4, 1e-10), (0.04, 0.03), ("N m/rad", "kg"))
    held = bounds.unsupported(*args)
    kept = bounds.unsupported(*args, held=False)
    assert list(held) == list(kept) == ["m_1"]
    assert "held at the start" in held["m_1"] and "ran off to its bound" in held["m_1"]
    assert "held" not in kept["m_1"] and "not fitted again" in kept["m_1"]
    below = bounds.unsupported(("m_1",), ("m",), (-0.01,), (0.001,), (0.03,), ("kg",), held=False)
    assert "below its physical bound 0 (not fitted again)" in below["m_1"]


def _write_robot_args(tmp_path):
    from alpes_dyn.model.spec import Motor, TransmissionSpec

    urdf = tmp_path / "finger.urdf"
    urdf.write_text(ad.urdf_string("finger3"))
    spec = tmp_path / "finger.toml"
    spec.write_text(TransmissionSpec(motors=(Motor("m", {"j1": 1.0, "j2": 1.0, "j3": 1.0}),)).to_toml())
    return argparse.Namespace(model=str(urdf), spec=str(spec), mjcf=None, output=str(tmp_path / "ident.toml"))


def test_the_urdf_beside_identify_o_is_named_where_it_is_replaced(tmp_path, monkeypatch):
    """identify -o FILE.toml on a URDF robot with masses writes FILE.urdf beside it: where one existed, a warning
    names it (the CLI's one ``alpes-dyn: warning:`` line), never a silent replacement; a new one, no warning."""
    from alpes_dyn.cli import fitting
    from alpes_dyn.estimation.identification import identified_spec

    monkeypatch.setattr(identified_spec, "spec_misfits", lambda model, names: ("m_j1",))
    monkeypatch.setattr(identified_spec, "identified_urdf", lambda res, text: "<robot name='fitted'/>\n")
    monkeypatch.setattr(identified_spec, "identified_spec", lambda res, base, masses: None)
    monkeypatch.setattr(identified_spec, "write_identified_spec",
                        lambda res, base, path, masses: open(path, "w").write("# spec\n"))
    args = _write_robot_args(tmp_path)
    res = type("Res", (), {"model": None, "names": ("m_j1",)})()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fitting._write_robot(res, args)
    assert not [w for w in caught if issubclass(w.category, AlpesDynWarning)]
    urdf = tmp_path / "ident.urdf"
    assert urdf.read_text() == "<robot name='fitted'/>\n"
    urdf.write_text("<robot name='mine'/>\n")
    with pytest.warns(AlpesDynWarning, match=r"-o: .*ident\.urdf \(the URDF with the fit's masses beside "
                                             r".*ident\.toml\) existed and is replaced"):
        fitting._write_robot(res, args)
    assert urdf.read_text() == "<robot name='fitted'/>\n"


def test_the_per_orientation_floor_matches_what_identify_needs():
    """experiment --rig both refuses a duration whose orientations get fewer than 100 samples each; at 100 each
    (0.2 s) the design is accepted, and every orientation's run holds the lines of the excitation (torque_lines
    needs more than 4 (2 lines + 1) samples a run)."""
    two = ((0.0, 0.0, -9.81), (9.81, 0.0, 0.0))
    with pytest.raises(InputError, match="75 samples to each of the 2 orientations"):
        ExperimentDesign(duration=0.15, orientations=two).check()
    design = ExperimentDesign(duration=0.2, orientations=two).check()
    assert design.n_samples // 2 >= 100 and 4 * (2 * len(design.lines) + 1) < 100
    assert math.isclose(design.duration, 0.2) and np.size(design.lines) > 0


def test_the_observer_check_of_a_record_too_short_for_the_nees_is_made_without_it():
    """identify's observer check on a simulated record with true joints: the joints' NEES (for the record only) is
    made where two of its samples, NEES_EVERY apart, follow the transient, else None -- not the former refusal
    "every: 0.1 s leaves 1 sample after 0.05 s", naming an option identify never had, of the 0.1 s record
    ``experiment --duration 0.1`` writes (100 samples, the floor)."""
    from alpes_dyn.estimation.identification.observer_check import observer_statistics

    model = ad.Model.alpes("finger2", friction=True)
    too_short = observer_statistics(experiment("finger2", design=ExperimentDesign(duration=0.1)), model)
    assert too_short.nees is None and math.isfinite(too_short.innovation_rms)
    made = observer_statistics(experiment("finger2", design=ExperimentDesign(duration=0.3)), model).nees
    assert made.samples == 2 and made.start == pytest.approx(0.15) and made.low < made.value < made.high
