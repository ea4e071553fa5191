"""The joint stops each joint gets, shown by ``alpes-dyn dynamics`` (issue 17): stiffness, damping and where they come
from (the Alpes stop, sized to the robot, per joint, none), against a pendulum's sizing computed by hand."""

from __future__ import annotations

import json
import math

import pytest

import alpes_dyn as ad
from alpes_dyn.model.stops import ALPES_STOP, stop_table
from test_robot_sizes import ARM, G0, IYY, MASS, PENDULUM_URDF, pendulum_spec


def _pendulum_files(tmp_path, urdf: str = PENDULUM_URDF) -> tuple[str, str]:
    u, s = tmp_path / "pendulum.urdf", tmp_path / "pendulum.toml"
    u.write_text(urdf)
    s.write_text(pendulum_spec())
    return str(u), str(s)


def test_dynamics_shows_the_pendulums_stops_as_sized_by_hand(tmp_path, capsys):
    """The pendulum (0.1 kg at 5 cm, horizontal at q = 0, limits +-1.5 rad, its spring resting at 0.3 rad): at its
    upper stop its weight pushes it up with m g l cos 1.5 = 3.47e-3 N m (its spring pulls it off both stops, so its
    weight alone sizes them: a motor may hold the spring's side), so k = that / 1.4 deg; d = 2 sqrt(k I) with I =
    m l^2 + I_yy its inertia about the axis. One joint: the per-joint sizing is the same."""
    from alpes_dyn.cli import main

    urdf, spec = _pendulum_files(tmp_path)
    assert main(["dynamics", "--model", urdf, "--spec", spec, "--json"]) == 0
    stops = json.loads(capsys.readouterr().out)["stops"]
    tau = MASS * G0 * ARM * math.cos(1.5)
    k = tau / math.radians(1.4)
    d = 2.0 * math.sqrt(k * (MASS * ARM**2 + IYY))
    for table in (stops["robot"], stops["per_joint"]):
        assert table["torque_into_stop"] == [pytest.approx(tau, rel=1e-9)]
        assert table["stiffness"] == [pytest.approx(k, rel=1e-9)] and table["damping"] == [pytest.approx(d, rel=1e-9)]
        assert table["source"] == ["sized"] and table["error"] is None
    assert k == pytest.approx(0.142, abs=1e-3)  # N m/rad: 14 times softer than the Alpes stop's 2
    assert main(["dynamics", "--model", urdf, "--spec", spec]) == 0
    text = capsys.readouterr().out.splitlines()
    row = text[text.index(next(line for line in text if line.startswith("joint stops"))) + 2].split()
    assert row[0] == "hinge" and float(row[4]) == pytest.approx(k, rel=1e-3) and row[6] == "sized"


def test_stop_sources_alpes_per_joint_and_none(tmp_path):
    """finger3 keeps the Alpes stop (2 N m/rad, 4e-3 N m s/rad) unless sized per joint; a hanging finger_edu's weight
    pulls its first two joints off their stops (tau* = 0): per joint they get the least k of the others; a pendulum
    with limits of 1e4 rad (none: beyond 1e3) has no stop to size, said in one line."""
    t = stop_table(ad.Model.alpes("finger3"))
    assert t["source"] == ["alpes"] * 3
    assert t["stiffness"] == [ALPES_STOP[0]] * 3 and t["damping"] == [ALPES_STOP[1]] * 3
    own = stop_table(ad.Model.alpes("finger3"), per_joint=True)
    assert own["source"] == ["sized"] * 3
    assert own["stiffness"] == pytest.approx([t / math.radians(1.4) for t in own["torque_into_stop"]], rel=1e-12)
    from alpes_dyn.model.spec import example_spec_path

    edu = stop_table(ad.Model.from_urdf_file(ad.example_robot_urdf("finger_edu"), example_spec_path("finger_edu")),
                     per_joint=True)
    assert edu["torque_into_stop"][:2] == [0.0, 0.0] and edu["source"] == ["least of the others"] * 2 + ["sized"]
    assert edu["stiffness"] == pytest.approx([edu["stiffness"][2]] * 3, rel=1e-12)
    free = ad.Model(PENDULUM_URDF.replace('lower="-1.5" upper="1.5"', 'lower="-1e4" upper="1e4"'))  # no stop
    none = stop_table(free)
    assert none["source"] == ["none"] and none["stiffness"] == [None]
    assert none["error"].startswith("stops: model 'pendulum' has no joint with a finite limit")
