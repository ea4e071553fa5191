"""Bad input gives a typed error with a one-line message that names the problem."""

from __future__ import annotations

import re

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.params import default_params_path

BASE = default_params_path().read_text()


def one_line(exc_info) -> str:
    msg = str(exc_info.value)
    assert "\n" not in msg
    return msg


@pytest.fixture(scope="module")
def finger():
    return ad.Model.alpes("finger3")


@pytest.mark.parametrize("q,pattern", [
    ([0.1, 0.2], r"q: expected shape \(3,\), got \(2,\)"),
    ([0.1, np.nan, 0.2], r"q: contains NaN or inf"),
    ([0.1, np.inf, 0.2], r"q: contains NaN or inf"),
    ("abc", r"q: expected 3 numbers"),
    (np.zeros((3, 1)), r"q: expected shape \(3,\)"),
])
def test_bad_vectors(finger, q, pattern):
    for method in (finger.inertia_matrix, finger.gravity_torque, finger.fingertip_jacobian,
                   lambda q: finger.frame_jacobian(q, "tip", "local"), lambda q: finger.frame_placement(q, "tip")):
        with pytest.raises(ad.InputError) as e:
            method(q)
        assert re.search(pattern, one_line(e))


def test_forward_dynamics_names_the_bad_input(finger):
    z = np.zeros(3)
    for name, args in (("q", (np.array([np.nan, 0, 0]), z, z)), ("v", (z, np.array([0, np.inf, 0.0]), z)),
                       ("tau", (z, z, np.array([0, 0, np.nan])))):
        with pytest.raises(ad.InputError, match=rf"^{name}: contains NaN"):
            finger.forward_dynamics(*args)
    with pytest.raises(ad.InputError, match=r"tau: expected shape \(3,\), got \(4,\)"):
        finger.forward_dynamics(z, z, np.zeros(4))
    with pytest.raises(ad.InputError, match=r"F: expected shape \(3,\)"):
        finger.forward_dynamics(z, z, z, F=[1.0, 2.0])
    with pytest.raises(ad.InputError, match=r"F: contains NaN"):
        finger.forward_dynamics(z, z, z, F=[0.0, 0.0, np.nan])


def test_unknown_names(finger):
    with pytest.raises(ad.ModelError, match=r"unknown model 'finger4'"):
        ad.Model.alpes("finger4")
    with pytest.raises(ad.ModelError, match=r"unknown tip/frame 'nail'"):
        finger.fingertip_jacobian(np.zeros(3), "nail")
    with pytest.raises(ad.ModelError, match=r"unknown spring model 'linear'"):
        ad.Model.alpes("finger3", spring="linear")
    with pytest.raises(ad.ModelError, match=r"unknown model"):
        ad.urdf_string("palm")


def write(tmp_path, text):
    p = tmp_path / "p.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("old,new,pattern", [
    ('m = { value = [0.03, 0.02, 0.023]', 'm = { value = [-0.03, 0.02, 0.023]', r"finger\.m: value must be > 0"),
    ('L = { value = [0.05, 0.03, 0.024]', 'L = { value = [0.05, 0.0, 0.024]', r"finger\.L: value must be > 0"),
    ('I = { value = [2.5e-5, 6.0e-6, 4.416e-6]', 'I = { value = [2.5e-6, 6.0e-6, 4.416e-6]',
     r"finger\.I: not physically consistent"),
    ('b = { value = 0.003,', 'bb = { value = 0.003,', r"finger\.bb: unknown key"),
    ('r_m = { value = 0.002, unit = "m", source = "assumed", reason = "small DC motor shaft; gives r/r_m = 2", ',
     'r_m = { value = 0.002, unit = "m", source = "assumed", ', r"transmission\.r_m\.reason: an assumed value needs"),
    ('K = { value = [0.04, 0.05, 0.06]', 'K = { value = [0.04, 0.05]', r"finger\.K: value must be a list of 3"),
    ('[friction]', '[frictions]', r"frictions: unknown section"),
    ('gravity = { value = [0.0, 0.0, -9.81]', 'gravity = { value = [0.0, 0.0, "down"]', r"environment\.gravity"),
    ('s = { value = [0.025, 0.015, 0.012]', 's = { value = [0.025, 0.015, 0.012', r"invalid TOML"),
])
def test_broken_parameter_file(tmp_path, old, new, pattern):
    assert old in BASE
    with pytest.raises(ad.ModelError) as e:
        ad.load_params(write(tmp_path, BASE.replace(old, new, 1)))
    assert re.search(pattern, one_line(e))


def test_missing_field_and_file(tmp_path):
    text = "\n".join(l for l in BASE.splitlines() if not l.startswith("b = "))
    with pytest.raises(ad.ModelError, match=r"^finger\.b: missing field$"):
        ad.load_params(write(tmp_path, text))
    with pytest.raises(ad.ModelError, match=r"cannot be read"):
        ad.load_params(tmp_path / "nope.toml")


def test_broken_urdf(tmp_path):
    with pytest.raises(ad.ModelError) as e:
        ad.Model("<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
                 "<child link='b'/></joint></robot>")
    assert one_line(e).startswith("URDF could not be parsed")
    with pytest.raises(ad.ModelError, match=r"expected URDF text"):
        ad.Model("not xml")
    with pytest.raises(ad.ModelError, match=r"no movable joint"):
        ad.Model("<robot name='x'><link name='a'/></robot>")
    with pytest.raises(ad.ModelError, match=r"cannot be read"):
        ad.Model.from_urdf_file(tmp_path / "missing.urdf")
    with pytest.raises(ad.ModelError, match=r"gravity: expected 3 finite numbers"):
        ad.Model(ad.urdf_string("finger2"), gravity=[0.0, -9.81])


def test_params_record_assumptions():
    p = ad.load_params()
    report = {k for k, v in p.raw.items() if v.source == "report"}
    assert report == {f"finger.{k}" for k in ("L", "s", "m", "I", "r", "K", "b")}
    assert all(prm.reason for _, prm in p.assumptions())
    assert np.allclose(p.finger.I, p.finger.m * p.finger.L**2 / 3, rtol=1e-12)
