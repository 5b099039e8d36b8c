"""Independent references for the free-floating dynamics: Pinocchio and MuJoCo on one URDF.

Each reference reads the whole system (bus, mounts, arms) from a URDF through its own
parser, puts a free joint on ``bus`` (the URDF's root link) with zero gravity, and turns
its answers into our conventions (`spacearm.dynamics`): nu = [v of the bus centroid; w of
the bus; qd] with v, w in bus axes; bus wrench = force at the bus centroid and torque about
it, bus axes; momentum [P; L about the system centroid], inertial axes.

- Pinocchio's free-flyer velocity is LOCAL at the bus origin: nu_ours = T nu_pin with
  T = [[I, -[c]x, 0], [0, I, 0], [0, 0, I]], c the bus centroid in the bus frame, so
  H_pin = T^T H T and F_pin = T^T F (power is invariant).
- MuJoCo's free-joint velocity is [v of the bus origin, WORLD axes; w, BODY axes]:
  nu_mj = S nu_pin with S = blkdiag(R, I, I), so nu_mj = W nu_ours with W = S T^-1,
  H_mj = W^-T H W^-1 and F = W^T F_mj.

The planar system of Umetani & Yoshida 1990 (Table 1) is written here as a URDF of
z-axis revolute joints from the paper's numbers (`planar_urdf`); its dynamics are the
in-plane rows [x, y, rz] of the spatial ones (``keep``).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import yaml

import spacearm as sa
from spacearm.models.spatial import locate_package_file

from .spatial_references import combined_urdf, pinocchio_configuration, random_chain_urdf
from .tree_references import system_urdf

PLANAR_KEEP = (0, 1, 5)
SPATIAL_KEEP = (0, 1, 2, 3, 4, 5)


def hat(c) -> np.ndarray:
    return np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _link(parent, name, mass, com, inertia):
    link = ET.SubElement(parent, "link", name=name)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(mass)))
    I = np.asarray(inertia, dtype=float)
    pairs = zip(
        ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)), strict=True
    )
    ET.SubElement(inertial, "inertia", **{k: repr(float(I[i, j])) for k, (i, j) in pairs})


def _fixed_or_revolute(parent, name, kind, parent_link, child_link, xyz):
    joint = ET.SubElement(parent, "joint", name=name, type=kind)
    ET.SubElement(joint, "origin", xyz=_fmt(xyz), rpy="0 0 0")
    ET.SubElement(joint, "parent", link=parent_link)
    ET.SubElement(joint, "child", link=child_link)
    if kind == "revolute":
        ET.SubElement(joint, "axis", xyz="0 0 1")
        ET.SubElement(joint, "limit", lower="-100", upper="100", effort="1", velocity="1")


def planar_urdf(paper: dict) -> tuple[str, list[str], str]:
    """The planar chain of a paper-style mapping (``base: {mass, inertia, attach}``, ``links:
    [{mass, inertia, a, b}]``) as a spatial URDF: the bus centroid at the bus origin, joint 1
    at b0 along the bus x axis, link i's centroid a_i along its x axis and the next joint (or
    the tip frame) at a_i + b_i, every joint a revolute about z. The plane's inertia is the
    z moment; the out-of-plane moments are set equal to it (a valid, symmetric body).

    Returns:
        (urdf text, joint names, tip frame name)
    """
    robot = ET.Element("robot", name="planar")
    base = paper["base"]
    _link(robot, "bus", base["mass"], np.zeros(3), np.eye(3) * float(base["inertia"]))
    parent, offset, names = "bus", float(base["attach"]), []
    for i, link in enumerate(paper["links"], start=1):
        names.append(f"joint{i}")
        _fixed_or_revolute(robot, f"joint{i}", "revolute", parent, f"link{i}", [offset, 0.0, 0.0])
        _link(robot, f"link{i}", link["mass"], [float(link["a"]), 0.0, 0.0], np.eye(3) * float(link["inertia"]))
        parent, offset = f"link{i}", float(link["a"]) + float(link["b"])
    ET.SubElement(robot, "link", name="tip")
    _fixed_or_revolute(robot, "tip_joint", "fixed", parent, "tip", [offset, 0.0, 0.0])
    return ET.tostring(robot, encoding="unicode"), names, "tip"


def _centroid_shift(bus_com, n: int) -> np.ndarray:
    """T of the module docstring, ``(6 + n, 6 + n)``: nu_ours = T nu_pin."""
    T = np.eye(6 + n)
    T[:3, 3:6] = -hat(bus_com)
    return T


def _rotate6(R, x):
    return np.concatenate([R @ x[:3], R @ x[3:]])


class PinocchioSystem:
    """Pinocchio's free-flyer model of a whole-system URDF whose root link is the bus.

    Args:
        urdf_text: the system URDF.
        bus_com: the bus centroid in the bus frame (where our base velocity is taken).
        joint_names: our joint order (Pinocchio's names).
        tips: tip frame names, in our tip order.
        keep: the twist components our kernels keep (planar: [x, y, rz]).
    """

    def __init__(self, urdf_text, *, bus_com, joint_names, tips, keep=SPATIAL_KEEP):
        import pinocchio as pin

        self.pin = pin
        self.model = pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
        self.model.gravity.linear[:] = 0.0
        self.data = self.model.createData()
        self.joints = [self.model.joints[self.model.getJointId(name)] for name in joint_names]
        self.n = len(self.joints)
        assert self.model.nv == 6 + self.n
        self.order = np.array(list(range(6)) + [joint.idx_v for joint in self.joints])
        self.tips = [self.model.getFrameId(name) for name in tips]
        self.keep = np.asarray(keep)
        self.T = _centroid_shift(np.asarray(bus_com, dtype=float), self.n)
        self.Ti = np.linalg.inv(self.T)

    def config(self, q, R):
        root = np.r_[np.zeros(3), self.pin.Quaternion(np.asarray(R)).coeffs()]
        return pinocchio_configuration(self.model, self.joints, q, root)

    def _pin(self, x):
        """A vector in our order (6 + n) -> Pinocchio's order."""
        out = np.zeros(self.model.nv)
        out[self.order] = x
        return out

    def _ours(self, x):
        return np.asarray(x)[self.order]

    def embed(self, x):
        out = np.zeros(6)
        out[self.keep] = x
        return out

    def coords(self):
        return np.concatenate([self.keep, 6 + np.arange(self.n)])

    def state(self, q, qd, tau, R, momentum, impulse, tip=0):
        """Every reference quantity at one state, in our conventions (module docstring).

        ``momentum`` and ``impulse`` carry the kept components only. The accelerations the
        inverse modes are asked for are ``qdd`` of the free system under ``tau`` (from ``aba``).
        """
        pin, model, data, Ti = self.pin, self.model, self.data, self.Ti
        config = self.config(q, R)
        M = pin.crba(model, data, config)
        M = np.triu(M) + np.triu(M, 1).T
        Mo = M[np.ix_(self.order, self.order)]
        coords = self.coords()
        out = {"mass_matrix": (Ti.T @ Mo @ Ti)[np.ix_(coords, coords)]}
        # Base velocity from the centroidal map: A_g nu_pin = [P; L about the centroid], world axes.
        A = self._ours_columns(pin.computeCentroidalMap(model, data, config))
        base_pin = np.linalg.solve(A[:, :6], self.embed(momentum) - A[:, 6:] @ qd)
        nu_pin = np.concatenate([base_pin, qd])
        out["base_velocity"] = (self.T @ nu_pin)[self.keep]
        bias = Ti.T @ self._ours(pin.nonLinearEffects(model, data, config, self._pin(nu_pin)))  # c = T^-T c_pin
        out["bias_forces"] = bias[coords]
        H = Ti.T @ Mo @ Ti
        coupling = np.linalg.solve(H[:6, :6], np.c_[H[:6, 6:], bias[:6]])  # H_b^-1 [H_bm, c_b]
        out["arm_inertia"] = H[6:, 6:] - H[6:, :6] @ coupling[:, :-1]
        out["reduced_bias"] = bias[6:] - H[6:, :6] @ coupling[:, -1]
        qdd = self._ours(pin.aba(model, data, config, self._pin(nu_pin), self._pin(np.r_[np.zeros(6), tau])))[6:]
        out["forward_dynamics"] = qdd
        out["qdd"] = qdd
        held = self._ours(
            pin.rnea(model, data, config, self._pin(np.r_[np.zeros(6), qd]), self._pin(np.r_[np.zeros(6), qdd]))
        )
        held = Ti.T @ held  # F_ours = T^-T F_pin
        out["held_tau"], out["held_wrench"] = held[6:], held[:6][self.keep]
        out["attitude_tau"], out["attitude_wrench"] = self._attitude(config, Mo, qd, qdd, R, self.embed(momentum))
        pin.computeJointJacobians(model, data, config)
        pin.updateFramePlacements(model, data)
        J = np.array(
            [self._ours_columns(pin.getFrameJacobian(model, data, f, pin.LOCAL_WORLD_ALIGNED)) for f in self.tips]
        )
        G = np.einsum("kij,kjl->kil", J, np.linalg.solve(Mo, np.swapaxes(J, 1, 2)))
        Gl = np.einsum("kij,kjl->kil", J[:, :, :6], np.linalg.solve(Mo[:6, :6], np.swapaxes(J[:, :, :6], 1, 2)))
        rows = np.ix_(np.arange(len(self.tips)), self.keep, self.keep)
        out["G_free"], out["G_locked"] = G[rows], Gl[rows]
        out["tip_velocity"] = (J @ nu_pin)[:, self.keep]
        jump = np.linalg.solve(Mo, J[tip].T @ self.embed(impulse))
        out["impulse_dqd"] = jump[6:]
        out["impulse_dbase"] = _rotate6(R, (self.T @ jump)[:6])[self.keep]
        locked = np.linalg.solve(Mo[:6, :6], J[tip][:, :6].T @ self.embed(impulse))
        out["impulse_locked_dbase"] = _rotate6(R, self.T[:6, :6] @ locked)[self.keep]
        return out

    def _ours_columns(self, matrix):
        return np.asarray(matrix)[:, self.order]

    def _attitude(self, config, Mo, qd, qdd, R, momentum):
        """Wheels hold the attitude: w = w' = 0, the linear momentum is P and no force acts on
        the bus. With w = 0 the bus origin and centroid move alike, so in Pinocchio's
        coordinates v solves m_tot v = R^T P - M_vq qd and v' the zero-force rows of
        crba + nonLinearEffects; rnea then gives the torque the wheels apply."""
        pin, model, data = self.pin, self.model, self.data
        v = np.linalg.solve(Mo[:3, :3], R.T @ momentum[:3] - Mo[:3, 6:] @ qd)
        nu = np.r_[v, np.zeros(3), qd]
        bias = self._ours(pin.nonLinearEffects(model, data, config, self._pin(nu)))
        v_dot = np.linalg.solve(Mo[:3, :3], -(Mo[:3, 6:] @ qdd + bias[:3]))
        forces = self._ours(pin.rnea(model, data, config, self._pin(nu), self._pin(np.r_[v_dot, np.zeros(3), qdd])))
        assert np.abs(forces[:3]).max() <= 1e-9 * max(1.0, np.abs(forces).max())
        forces = self.Ti.T @ forces
        return forces[6:], forces[:6][self.keep]


class MujocoSystem:
    """MuJoCo's model of the same URDF (`tests.spatial_references.mujoco_model`), in our conventions."""

    def __init__(self, model, *, bus_com, joint_names, keep=SPATIAL_KEEP):
        import mujoco

        self.mujoco = mujoco
        self.model = model
        self.data = mujoco.MjData(model)
        self.n = len(joint_names)
        assert model.nv == 6 + self.n
        self.joint_qpos = [model.jnt_qposadr[model.joint(name).id] for name in joint_names]
        self.order = np.array(list(range(6)) + [model.jnt_dofadr[model.joint(name).id] for name in joint_names])
        self.keep = np.asarray(keep)
        self.Ti = np.linalg.inv(_centroid_shift(np.asarray(bus_com, dtype=float), self.n))
        self.bus = model.body("bus").id

    def _set(self, q, R, nu_ours=None):
        mj, data = self.mujoco, self.data
        data.qpos[:] = 0.0
        quaternion = np.zeros(4)
        mj.mju_mat2Quat(quaternion, np.asarray(R, dtype=float).ravel())
        data.qpos[3:7] = quaternion
        data.qpos[self.joint_qpos] = q
        W = np.eye(6 + self.n)
        W[:3, :3] = R
        W = W @ self.Ti  # nu_mj = W nu_ours
        data.qvel[:] = 0.0
        if nu_ours is not None:
            data.qvel[self.order] = W @ nu_ours
        return W

    def _momentum_map(self, q, R):
        """``(6, 6 + n)`` [P; L about the system centroid] per nu_ours, from mj_subtreeVel at the bus."""
        mj, model, data = self.mujoco, self.model, self.data
        total = model.body_subtreemass[self.bus]
        columns = []
        for i in range(6 + self.n):
            self._set(q, R, np.eye(6 + self.n)[i])
            mj.mj_forward(model, data)
            mj.mj_subtreeVel(model, data)
            columns.append(np.r_[total * data.subtree_linvel[self.bus], data.subtree_angmom[self.bus]])
        return np.array(columns).T

    def state(self, q, qd, tau, R, momentum):
        """H (mj_fullM), the base velocity (subtree momenta), qdd (mj_forward) and the held
        wrench and torques (mj_inverse) at one state, our conventions."""
        mj, model, data = self.mujoco, self.model, self.data
        embedded = np.zeros(6)
        embedded[self.keep] = momentum
        A = self._momentum_map(q, R)
        base = np.linalg.solve(A[:, :6], embedded - A[:, 6:] @ qd)
        W = self._set(q, R, np.r_[base, qd])
        data.qfrc_applied[:] = 0.0
        data.qfrc_applied[self.order[6:]] = tau
        mj.mj_forward(model, data)
        M = np.zeros((model.nv, model.nv))
        mj.mj_fullM(model, data, M)
        M = M[np.ix_(self.order, self.order)]
        coords = np.concatenate([self.keep, 6 + np.arange(self.n)])
        out = {
            "mass_matrix": (W.T @ M @ W)[np.ix_(coords, coords)],
            "base_velocity": base[self.keep],
            "forward_dynamics": np.array(data.qacc[self.order[6:]]),
        }
        qdd = out["forward_dynamics"]
        data.qfrc_applied[:] = 0.0
        W = self._set(q, R, np.r_[np.zeros(6), qd])
        data.qacc[:] = 0.0
        data.qacc[self.order[6:]] = qdd
        mj.mj_inverse(model, data)
        forces = W.T @ np.asarray(data.qfrc_inverse)[self.order]  # F_ours = W^T F_mj
        out["held_tau"], out["held_wrench"] = forces[6:], forces[:6][self.keep]
        return out


# The four systems of the dynamics tests: our robot, the URDF the references read, their names ----
#
# Each builder takes a folder for the files it writes and returns (robot, system URDF text,
# the keyword arguments of `PinocchioSystem` but the URDF: bus_com, joint_names, tips[, keep]).

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
UR5 = "robots/ur_description/urdf/ur5_robot.urdf"


def _config(name):
    with open(os.path.join(CONFIGS, name), encoding="utf-8") as handle:
        return yaml.safe_load(handle)


def _ur5_text():
    try:
        path = locate_package_file("test", "example-robot-data", UR5)
    except Exception:
        pytest.skip("example-robot-data is not installed")
    with open(path, encoding="utf-8") as handle:
        return handle.read()


def _planar(tmp_path):
    paper = _config("umetani1990.yaml")
    text, names, tip = planar_urdf(paper)
    return sa.umetani1990(), text, {"bus_com": np.zeros(3), "joint_names": names, "tips": [tip], "keep": PLANAR_KEEP}


def _ur5(tmp_path):
    config = _config("ur5-smallsat.yaml")
    base, mount = config["base"], config["mount"]
    text = combined_urdf(
        _ur5_text(),
        root_link="base_link",
        base_mass=base["mass"],
        base_com=base["com"],
        base_inertia=base["inertia"],
        mount_xyz=mount["xyz"],
        mount_rpy=mount["rpy"],
    )
    robot = sa.load_robot(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    return robot, text, {"bus_com": base["com"], "joint_names": list(robot.joint_names), "tips": ["tool0"]}


def _dual_ur5(tmp_path):
    config = _config("dual-ur5-servicer.yaml")
    base, ur5 = config["base"], _ur5_text()
    arms = [(arm["name"] + "_", ur5, "base_link", arm["mount"]["xyz"], arm["mount"]["rpy"]) for arm in config["arms"]]
    text = system_urdf(base_mass=base["mass"], base_com=base["com"], base_inertia=base["inertia"], arms=arms)
    robot = sa.load_robot(os.path.join(CONFIGS, "dual-ur5-servicer.yaml"))
    names = [name.replace("/", "_") for name in robot.joint_names]
    tips = [name.replace("/", "_") for name in robot.tip_names]
    return robot, text, {"bus_com": base["com"], "joint_names": names, "tips": tips}


RANDOM_BUS = {
    "base_mass": 150.0,
    "base_com": [0.12, -0.18, 0.07],
    "base_inertia": [[21.0, 1.4, -2.1], [1.4, 17.5, 0.9], [-2.1, 0.9, 14.2]],  # principal axes rotated
    "mount_xyz": [0.45, -0.2, 0.35],
    "mount_rpy": [0.4, -0.6, 1.2],  # tilted
}


def _random7(tmp_path):
    text, names, lock, tip = random_chain_urdf(np.random.default_rng(7), 7)
    (tmp_path / "random7.urdf").write_text(text, encoding="utf-8")
    bus = RANDOM_BUS
    (tmp_path / "random7.yaml").write_text(
        "name: random7\n"
        f"base: {{mass: {bus['base_mass']}, com: {bus['base_com']}, inertia: {bus['base_inertia']}}}\n"
        f"mount: {{xyz: {bus['mount_xyz']}, rpy: {bus['mount_rpy']}}}\n"
        f"arm: {{urdf: random7.urdf, root_link: root, tip: {tip}, lock_joints: {lock}}}\n",
        encoding="utf-8",
    )
    robot = sa.load_robot(tmp_path / "random7.yaml")
    assert list(robot.joint_names) == names
    combined = combined_urdf(text, root_link="root", lock_joints=lock, **bus)
    return robot, combined, {"bus_com": bus["base_com"], "joint_names": names, "tips": [tip]}


BUILDERS = {"planar": _planar, "ur5": _ur5, "dual_ur5": _dual_ur5, "random7": _random7}
