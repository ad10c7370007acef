"""The URDF export: Pinocchio and rerun load it as the same robot nfarm computes with."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
from hypothesis import given

from conftest import random_chains
from nfarm.pinocchio_ref import pinocchio_from_urdf, pinocchio_model
from nfarm.urdf import to_urdf

TOL = 1e-12


@given(random_chains())
def test_urdf_loads_into_pinocchio_as_the_same_robot(robot):
    """to_urdf → Pinocchio gives the same kinematics and dynamics as the model built from DH."""
    direct, urdf = pinocchio_model(robot), pinocchio_from_urdf(to_urdf(robot))
    urdf.model.gravity.linear = robot.gravity
    rng = np.random.default_rng(0)
    for q, v, a in rng.uniform(-2, 2, (5, 3, robot.n)):
        np.testing.assert_allclose(urdf.fk_all(q), direct.fk_all(q), atol=TOL)
        np.testing.assert_allclose(urdf.fk(q), direct.fk(q), atol=TOL)
        tau_urdf = pin.rnea(urdf.model, urdf.data, q, v, a)
        tau_direct = pin.rnea(direct.model, direct.data, q, v, a)
        np.testing.assert_allclose(tau_urdf, tau_direct, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(urdf.model.lowerPositionLimit, robot.qlim[:, 0])
    np.testing.assert_allclose(urdf.model.upperPositionLimit, robot.qlim[:, 1])


def test_urdf_structure(robot):
    root = ET.fromstring(to_urdf(robot))
    assert root.get("name") == robot.name
    revolute = [j for j in root.iter("joint") if j.get("type") == "revolute"]
    assert [j.get("name") for j in revolute] == list(robot.joint_names)
    masses = [float(link.find("inertial/mass").get("value"))
              for link in root.iter("link") if link.find("inertial") is not None]
    np.testing.assert_array_equal(masses, robot.mass)
    for i in range(robot.n):
        assert root.find(f"link[@name='link{i + 1}']/visual") is not None


def test_rerun_loads_the_urdf(intelbot5, tmp_path):
    """rerun's own URDF loader (inside the SDK, no viewer) turns every link into geometry."""
    urdf = tmp_path / "intelbot5.urdf"
    urdf.write_text(to_urdf(intelbot5))
    rrd = tmp_path / "robot.rrd"
    script = ("import rerun as rr, sys\n"
              "rec = rr.RecordingStream('nfarm-test', recording_id='urdf')\n"
              "rec.save(sys.argv[2])\n"
              "rec.log_file_from_path(sys.argv[1], static=True)\n"
              "rec.flush()\n")
    subprocess.run([sys.executable, "-c", script, str(urdf), str(rrd)], check=True)
    rerun = [sys.executable, "-m", "rerun", "rrd", "print", str(rrd)]
    printed = subprocess.run(rerun, check=True, capture_output=True, text=True).stdout
    for i in range(intelbot5.n):
        assert f"/intelbot5/visual_geometries/link{i + 1}/visual_0" in printed
    assert "Cylinders3D" in printed
