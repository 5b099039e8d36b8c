"""A rigid payload welded to a tip (`spacearm.with_payload`) and a grasped target as one
(`spacearm.grasped_robot`, `spacearm.system_momentum`), against independent references.

- Pinocchio reads each system's URDF with the payload written as one more link on a fixed
  joint below the tip link (tests/dynamics_references.py's conventions): its mass matrix
  equals ours of the payload robot, on the UR5 smallsat, two UR5 on one bus (tip 1) and the
  paper's planar system (a payload on the last link's line, one that moves the link's
  centroid beyond its tip too).
- The planar merge against the hand-computed link (Umetani & Yoshida 1990's a, b, m, I) and
  the whole system's mass and rotational inertia about the bus centroid summed body by body.
- A rigid grasp conserves the momentum of robot and target: the combined robot's momentum at
  the post-grasp state (`spacearm.capture`'s bus velocity and joint rates) equals the robot's
  own momentum before plus the target's (its centroid's linear momentum and its spin about
  the combined centroid), free and locked; Pinocchio's combined system with that momentum
  moves its bus as capture says.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import jax
import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm._core.groups import rpy_matrix
from spacearm.models.spatial import locate_package_file

from .dynamics_references import PLANAR_KEEP, PinocchioSystem, _fixed_or_revolute, _link, planar_urdf
from .spatial_references import config_urdf, random_rotation
from .tree_references import system_urdf

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
UR5 = os.path.join(CONFIGS, "ur5-smallsat.yaml")
DUAL = os.path.join(CONFIGS, "dual-ur5-servicer.yaml")
TOLERANCE = 1e-12  # relative to the reference's largest entry


def _yaml(path) -> dict:
    with open(path, encoding="utf-8") as handle:
        return yaml.safe_load(handle)


def _with_payload_link(text: str, tip_link: str, mass, com, inertia) -> str:
    """The URDF with a ``payload`` link on a fixed joint at ``tip_link``'s frame (its centroid
    and inertia in that frame): Pinocchio merges it into the tip's body itself."""
    robot = ET.fromstring(text)
    _link(robot, "payload", mass, com, inertia)
    _fixed_or_revolute(robot, "payload_joint", "fixed", tip_link, "payload", np.zeros(3))
    return ET.tostring(robot, encoding="unicode")


def _ur5_system(payload):
    pytest.importorskip("pinocchio")
    robot = sa.load_robot(UR5)
    text, bus_com = config_urdf(UR5)
    text = _with_payload_link(text, "tool0", *payload)
    return robot, PinocchioSystem(text, bus_com=bus_com, joint_names=list(robot.joint_names), tips=["tool0"])


def _dual_system(payload):
    pytest.importorskip("pinocchio")
    robot = sa.load_robot(DUAL)
    config = _yaml(DUAL)
    base = config["base"]
    arms = []
    for arm in config["arms"]:
        urdf = locate_package_file(DUAL, arm["urdf"]["package"], arm["urdf"]["path"])
        with open(urdf, encoding="utf-8") as handle:
            arms.append((arm["name"] + "_", handle.read(), arm["root_link"], arm["mount"]["xyz"], arm["mount"]["rpy"]))
    text = system_urdf(base_mass=base["mass"], base_com=base["com"], base_inertia=base["inertia"], arms=arms)
    text = _with_payload_link(text, "right_tool0", *payload)
    names = [name.replace("/", "_") for name in robot.joint_names]
    tips = [name.replace("/", "_") for name in robot.tip_names]
    return robot, PinocchioSystem(text, bus_com=base["com"], joint_names=names, tips=tips)


def _planar_system(payload):
    pytest.importorskip("pinocchio")
    text, names, tip = planar_urdf(_yaml(os.path.join(CONFIGS, "umetani1990.yaml")))
    text = _with_payload_link(text, tip, *payload)
    return sa.umetani1990(), PinocchioSystem(text, bus_com=np.zeros(3), joint_names=names, tips=[tip], keep=PLANAR_KEEP)


def _random_payload(rng, mass):
    """A valid rigid body: principal moments of a box, turned to random axes; its centroid off the tip."""
    half = rng.uniform(0.1, 0.4, size=3)
    moments = (
        mass / 3.0 * np.array([half[1] ** 2 + half[2] ** 2, half[0] ** 2 + half[2] ** 2, half[0] ** 2 + half[1] ** 2])
    )
    axes = random_rotation(rng)
    return mass, rng.uniform(-0.3, 0.3, size=3), axes @ np.diag(moments) @ axes.T


def _reference_state(system, q, R):
    n = len(q)
    return system.state(q, np.zeros(n), np.zeros(n), R, np.zeros(len(system.keep)), np.zeros(len(system.keep)))


def _assert_close(ours, reference, tolerance=TOLERANCE):
    ours, reference = np.asarray(ours), np.asarray(reference)
    scale = np.abs(reference).max()
    assert np.abs(ours - reference).max() <= tolerance * scale, np.abs(ours - reference).max() / scale


@pytest.mark.parametrize("which", ["ur5", "dual_ur5"])
def test_mass_matrix_of_the_payload_robot_is_pinocchios_with_a_payload_link(which):
    """H of with_payload's robot equals Pinocchio's of the URDF with the payload link, three postures."""
    rng = np.random.default_rng(11 if which == "ur5" else 12)
    payload = _random_payload(rng, 37.0)
    robot, system = (_ur5_system if which == "ur5" else _dual_system)(payload)
    tip = 0 if which == "ur5" else 1
    carried = sa.with_payload(robot, *payload, tip=tip)
    assert type(carried) is type(robot)
    for _ in range(3):
        q, R = rng.uniform(-2.5, 2.5, robot.n_joints), random_rotation(rng)
        reference = _reference_state(system, q, R)["mass_matrix"]
        _assert_close(sa.mass_matrix(carried, q, base_rotation=R), reference)
    # The payload changed H: without it the same comparison fails by far.
    assert np.abs(np.asarray(sa.mass_matrix(robot, q, base_rotation=R)) - reference).max() > 1e-2


def test_a_tree_tip_by_name_and_the_other_arm_untouched():
    robot = sa.load_robot(DUAL)
    payload = _random_payload(np.random.default_rng(5), 12.0)
    by_index, by_name = sa.with_payload(robot, *payload, tip=1), sa.with_payload(robot, *payload, tip="right/tool0")
    np.testing.assert_array_equal(by_index.link_inertia, by_name.link_inertia)
    changed = np.flatnonzero(np.asarray(by_index.link_mass) != np.asarray(robot.link_mass))
    assert changed.tolist() == [robot.tip_bodies[1]]
    with pytest.raises(sa.ConfigError, match="tip 'middle/tool0'"):
        sa.with_payload(robot, *payload, tip="middle/tool0")
    with pytest.raises(sa.ConfigError, match="tip 3"):
        sa.with_payload(robot, *payload, tip=3)


@pytest.mark.parametrize("mass, along", [(80.0, 0.4), (200.0, 1.0)])
def test_planar_payload_on_the_link_line(mass, along):
    """The merged link by hand and the system's mass matrix by Pinocchio. The heavier payload puts
    the combined centroid beyond the tip (b < 0): the planar kernels take it as a signed length."""
    robot, system = _planar_system((mass, [along, 0.0, 0.0], 12.5 * np.eye(3)))
    carried = sa.with_payload(robot, mass, [along, 0.0], 12.5)
    a, b, m, inertia = 1.0, 1.0, 100.0, 33.3  # Table 1's last link
    centroid = (m * a + mass * (a + b + along)) / (m + mass)
    moment = inertia + m * (centroid - a) ** 2 + 12.5 + mass * (a + b + along - centroid) ** 2
    np.testing.assert_allclose(carried.link_a, [1.0, centroid], rtol=1e-15)
    np.testing.assert_allclose(carried.link_b, [1.0, a + b - centroid], rtol=1e-15)
    np.testing.assert_allclose(carried.link_mass, [100.0, m + mass], rtol=1e-15)
    np.testing.assert_allclose(carried.link_inertia, [33.3, moment], rtol=1e-15)
    phi = np.array([0.3, -0.8, 1.9])
    _assert_close(
        sa.mass_matrix(carried, phi), _reference_state(system, phi[1:], rpy_matrix([0, 0, phi[0]]))["mass_matrix"]
    )
    # Whole-system mass and rotational inertia about the bus centroid, body by body.
    theta = np.cumsum(phi)
    unit = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    joint2 = 1.4 * unit[0] + 2.0 * unit[1]  # b0 = 1.4, link 1 of length 2
    bodies = [(100.0, 1.4 * unit[0] + unit[1], 33.3), (100.0, joint2 + unit[2], 33.3)]
    bodies.append((mass, joint2 + (2.0 + along) * unit[2], 12.5))
    H = np.asarray(sa.mass_matrix(carried, phi))
    np.testing.assert_allclose(H[0, 0], 1000.0 + 200.0 + mass, rtol=1e-15)
    spin = 635.3 + sum(I + mk * float(c @ c) for mk, c, I in bodies)  # the bus's own moment 635.3
    np.testing.assert_allclose(H[2, 2], spin, rtol=1e-13)
    # The closed-form tip (the planar fast path) and the tree's agree at the signed lengths.
    np.testing.assert_allclose(sa.tip_position(carried, phi), sa.family_of(carried).tip(carried, phi))


def test_planar_payload_off_the_line_is_refused_or_nan_when_traced():
    robot = sa.umetani1990()
    with pytest.raises(sa.ConfigError, match="across the last link"):
        sa.with_payload(robot, 80.0, [0.4, -0.1], 12.5)
    traced = jax.jit(lambda com: sa.with_payload(robot, 80.0, com, 12.5).link_a)
    assert np.isnan(traced(np.array([0.4, -0.1]))[-1])
    np.testing.assert_allclose(traced(np.array([0.4, 0.0])), sa.with_payload(robot, 80.0, [0.4, 0.0], 12.5).link_a)


def test_jit_and_vmap_over_payloads():
    """The spatial merge is pure jnp: jit and vmap over the payload give the eager robots."""
    robot = sa.load_robot(UR5)
    rng = np.random.default_rng(3)
    payloads = [_random_payload(rng, m) for m in (5.0, 20.0, 60.0)]
    mass, com, inertia = (np.stack(x) for x in zip(*payloads, strict=True))
    batched = jax.jit(jax.vmap(lambda m, c, i: sa.with_payload(robot, m, c, i)))(mass, com, inertia)
    for k, payload in enumerate(payloads):
        eager = sa.with_payload(robot, *payload)
        for field in ("link_mass", "link_com", "link_inertia"):
            np.testing.assert_allclose(getattr(batched, field)[k], getattr(eager, field), rtol=1e-14, atol=1e-15)


def _client(rng, planar=False):
    if planar:
        return dict(mass=80.0, inertia=12.5, offset=None, velocity=np.array([0.05, -0.02, 0.03]))
    mass, offset, inertia = _random_payload(rng, 50.0)
    return dict(mass=mass, inertia=inertia, offset=offset, velocity=rng.uniform(-0.05, 0.05, 6))


def _momentum_before(robot, q, R, m, target, tip):
    """Robot's own momentum plus the target's, [P; L about the combined centroid], inertial axes."""
    p = np.asarray(sa.tip_position(robot, q, base_rotation=R))
    p = p[tip] if p.ndim == 2 else p
    planar = p.shape == (2,)
    offset, inertia = np.asarray(target["offset"], float), np.asarray(target["inertia"], float)
    if planar:
        p, offset, m = np.r_[p, 0.0], np.r_[offset, 0.0], np.r_[m[0], m[1], 0.0, 0.0, 0.0, m[2]]
        v = target["velocity"]
        velocity, inertia = np.r_[v[0], v[1], 0.0, 0.0, 0.0, v[2]], inertia * np.eye(3)
    else:
        velocity = target["velocity"]
    robot_mass = float(np.asarray(sa.mass_matrix(robot, q, base_rotation=R))[0, 0])
    centroid = p + offset  # about the robot's centroid
    combined = target["mass"] * centroid / (robot_mass + target["mass"])
    P_t = target["mass"] * velocity[:3]
    L = m[3:] - np.cross(combined, m[:3]) + inertia @ velocity[3:] + np.cross(centroid - combined, P_t)
    total = np.r_[m[:3] + P_t, L]
    return total[[0, 1, 5]] if planar else total


@pytest.mark.parametrize("which", ["ur5", "dual_ur5", "planar"])
@pytest.mark.parametrize("joints", ["free", "locked"])
def test_the_grasp_conserves_the_momentum_of_robot_and_target(which, joints):
    """system_momentum of grasped_robot at capture's (base_after, qd_after) equals the momentum before."""
    rng = np.random.default_rng({"ur5": 1, "dual_ur5": 2, "planar": 3}[which])
    tip = 1 if which == "dual_ur5" else 0
    if which == "planar":
        robot, R = sa.umetani1990(), None
        q = np.array([0.2, -1.0, 2.1])
        target = _client(rng, planar=True)
        theta = q.sum()
        target["offset"] = 0.4 * np.array([np.cos(theta), np.sin(theta)])  # on the last link's line
        m = np.array([3.0, -1.5, 2.0])
    else:
        robot = sa.load_robot(UR5 if which == "ur5" else DUAL)
        q, R = rng.uniform(-2.0, 2.0, robot.n_joints), random_rotation(rng)
        target, m = _client(rng), rng.normal(size=6)
    qd = rng.uniform(-0.3, 0.3, sa.family_of(robot).joint_count(robot))
    qd_after, base_after, _ = sa.capture(robot, q, qd, target, base_rotation=R, momentum=m, tip=tip, joints=joints)
    carried = sa.grasped_robot(robot, q, target, base_rotation=R, tip=tip)
    after = sa.system_momentum(carried, q, qd_after, base_after, base_rotation=R)
    before = _momentum_before(robot, q, R, m, target, tip)
    np.testing.assert_allclose(after, before, rtol=0, atol=1e-10 * max(1.0, np.abs(before).max()))
    # ... and the bus velocity that momentum gives the combined robot is capture's (the replay's start).
    nu = np.asarray(sa.base_velocity(carried, q, qd_after, base_rotation=R, momentum=after))
    if which == "planar":
        c, s = np.cos(q[0]), np.sin(q[0])
        nu = np.r_[c * nu[0] - s * nu[1], s * nu[0] + c * nu[1], nu[2]]
    else:
        nu = np.r_[R @ nu[:3], R @ nu[3:]]
    np.testing.assert_allclose(nu, base_after, rtol=0, atol=1e-12)


def test_pinocchio_moves_the_combined_bus_as_capture_says():
    """The UR5 holding a target (Pinocchio, the payload link in tip axes at the grasp) with the
    momentum before the grasp and capture's joint rates has capture's bus velocity."""
    rng = np.random.default_rng(8)
    robot = sa.load_robot(UR5)
    q, R, qd, m = rng.uniform(-2.0, 2.0, 6), random_rotation(rng), rng.uniform(-0.3, 0.3, 6), rng.normal(size=6)
    target = _client(rng)
    qd_after, base_after, _ = sa.capture(robot, q, qd, target, base_rotation=R, momentum=m)
    payload = sa.target_in_tip_frame(robot, q, target, base_rotation=R)
    _, system = _ur5_system((payload["mass"], np.asarray(payload["com"]), np.asarray(payload["inertia"])))
    before = _momentum_before(robot, q, R, m, target, 0)
    base = system.state(q, np.asarray(qd_after), np.zeros(6), R, before, np.zeros(6))["base_velocity"]
    _assert_close(np.r_[R @ base[:3], R @ base[3:]], base_after, 1e-10)
