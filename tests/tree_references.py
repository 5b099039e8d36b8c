"""Independent references for the tree family: Pinocchio and MuJoCo on one URDF of the system.

`system_urdf` writes the bus, one fixed mount joint per arm and each arm's links and
joints below its root link with a name prefix (two copies of one URDF coexist),
geometry stripped. `random_tree` writes a branched URDF with random revolute,
continuous and prismatic joints and random inertials, and the same system as a
`TreeRobot` built from the same numbers (not through any URDF reader). The references
put a free-floating joint on ``bus`` at the identity (world axes = bus axes) and
compute J* = J_m - J_b H_b^-1 H_bm per tip frame.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from spacearm.models.spatial.urdf import rpy_matrix
from spacearm.models.tree import TreeLabels, TreeRobot

from .spatial_references import pinocchio_configuration


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _inertial(parent, mass, com, inertia, rpy=(0.0, 0.0, 0.0)):
    inertial = ET.SubElement(parent, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(com), rpy=_fmt(rpy))
    ET.SubElement(inertial, "mass", value=repr(float(mass)))
    I = np.asarray(inertia, dtype=float)
    pairs = zip(
        ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)), strict=True
    )
    ET.SubElement(inertial, "inertia", **{k: repr(float(I[i, j])) for k, (i, j) in pairs})


def system_urdf(*, base_mass, base_com, base_inertia, arms) -> str:
    """One URDF: ``bus`` + per arm a fixed ``PREFIXmount`` joint to its prefixed root link.

    Args:
        arms: ``(prefix, urdf_text, root_link, mount_xyz, mount_rpy)`` per arm.
    """
    robot = ET.Element("robot", name="system")
    bus = ET.SubElement(robot, "link", name="bus")
    _inertial(bus, base_mass, base_com, base_inertia)
    for prefix, text, root_link, mount_xyz, mount_rpy in arms:
        tree = ET.fromstring(text)
        links = {e.get("name"): e for e in tree.findall("link")}
        children: dict[str, list] = {}
        for j in tree.findall("joint"):
            children.setdefault(j.find("parent").get("link"), []).append(j)
        mount = ET.SubElement(robot, "joint", name=f"{prefix}mount", type="fixed")
        ET.SubElement(mount, "origin", xyz=_fmt(mount_xyz), rpy=_fmt(mount_rpy))
        ET.SubElement(mount, "parent", link="bus")
        ET.SubElement(mount, "child", link=prefix + root_link)
        stack, keep_links, keep_joints = [root_link], [root_link], []
        while stack:
            for j in children.get(stack.pop(), []):
                keep_joints.append(j)
                child = j.find("child").get("link")
                keep_links.append(child)
                stack.append(child)
        for name in keep_links:
            link = ET.fromstring(ET.tostring(links[name]))
            link.set("name", prefix + name)
            for tag in ("visual", "collision"):
                for e in link.findall(tag):
                    link.remove(e)
            robot.append(link)
        for j in keep_joints:
            j = ET.fromstring(ET.tostring(j))
            j.set("name", prefix + j.get("name"))
            for tag in ("dynamics", "safety_controller", "calibration", "mimic"):
                for e in j.findall(tag):
                    j.remove(e)
            for tag in ("parent", "child"):
                j.find(tag).set("link", prefix + j.find(tag).get("link"))
            robot.append(j)
    return ET.tostring(robot, encoding="unicode")


# A random tree ----------------------------------------------------------------------------


def _random_inertia(rng, mass):
    """A valid inertia about the centroid (principal moments obeying the triangle inequality), its frame's rpy."""
    half = rng.uniform(0.03, 0.3, size=3)  # box half-sizes
    principal = (
        mass / 3 * np.array([half[1] ** 2 + half[2] ** 2, half[0] ** 2 + half[2] ** 2, half[0] ** 2 + half[1] ** 2])
    )
    rpy = rng.uniform(-np.pi, np.pi, size=3) * np.array([1.0, 0.45, 1.0])
    return principal, rpy


def random_tree(seed: int, *, torso: int = 2, branches=(3, 4, 2)):
    """``(urdf_text, TreeRobot)``: a bus, a torso chain of ``torso`` joints and one branch per
    entry of ``branches`` hanging from the torso's last body, each ending in a tip frame.

    Joint kinds are drawn from revolute (limited), continuous and prismatic; joint
    origins, axes and inertials are random. The TreeRobot is built from the same numbers.
    """
    rng = np.random.default_rng(seed)
    robot = ET.Element("robot", name=f"tree{seed}")
    bus = ET.SubElement(robot, "link", name="bus")
    base_mass = rng.uniform(50.0, 300.0)
    base_com = rng.uniform(-0.2, 0.2, size=3)
    principal, rpy = _random_inertia(rng, base_mass)
    R = rpy_matrix(rpy)
    base_inertia = R @ np.diag(principal) @ R.T
    _inertial(bus, base_mass, base_com, np.diag(principal), rpy)

    fields = {k: [] for k in ("rot", "xyz", "axis", "mass", "com", "inertia", "lower", "upper")}
    kinds, parents, urdf_types, names, tip_bodies = [], [], [], [], []
    tip_rot, tip_xyz = [], []

    def add_joint(parent_link, parent_index, name):
        kind = rng.choice(["revolute", "continuous", "prismatic"], p=[0.5, 0.25, 0.25])
        xyz = rng.uniform(-0.4, 0.4, size=3)
        rpy = rng.uniform(-np.pi, np.pi, size=3) * np.array([1.0, 0.45, 1.0])
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        mass = rng.uniform(1.0, 15.0)
        com = rng.uniform(-0.2, 0.2, size=3)
        principal, inertia_rpy = _random_inertia(rng, mass)
        Ri = rpy_matrix(inertia_rpy)
        joint = ET.SubElement(robot, "joint", name=name, type=str(kind))
        ET.SubElement(joint, "parent", link=parent_link)
        ET.SubElement(joint, "child", link=name + "_link")
        ET.SubElement(joint, "origin", xyz=_fmt(xyz), rpy=_fmt(rpy))
        ET.SubElement(joint, "axis", xyz=_fmt(axis))
        lower, upper = (-np.inf, np.inf) if kind == "continuous" else (-2.5, 2.5)
        if kind == "prismatic":
            lower, upper = -0.5, 0.5
        if kind != "continuous":
            ET.SubElement(joint, "limit", lower=repr(lower), upper=repr(upper), effort="10", velocity="1")
        link = ET.SubElement(robot, "link", name=name + "_link")
        _inertial(link, mass, com, np.diag(principal), inertia_rpy)
        for key, value in zip(
            fields,
            (rpy_matrix(rpy), xyz, axis, mass, com, Ri @ np.diag(principal) @ Ri.T, lower, upper),
            strict=True,
        ):
            fields[key].append(value)
        kinds.append("prismatic" if kind == "prismatic" else "revolute")
        parents.append(parent_index)
        urdf_types.append(str(kind))
        names.append(name)
        return name + "_link", len(names) - 1

    link, index = "bus", -1
    for i in range(torso):
        link, index = add_joint(link, index, f"torso{i}")
    torso_link, torso_index = link, index
    tips = []
    for b, length in enumerate(branches):
        link, index = torso_link, torso_index
        for i in range(length):
            link, index = add_joint(link, index, f"arm{b}_j{i}")
        xyz, rpy = rng.uniform(-0.2, 0.2, size=3), rng.uniform(-1.0, 1.0, size=3)
        tip = ET.SubElement(robot, "joint", name=f"tip{b}_fixed", type="fixed")
        ET.SubElement(tip, "parent", link=link)
        ET.SubElement(tip, "child", link=f"tip{b}")
        ET.SubElement(tip, "origin", xyz=_fmt(xyz), rpy=_fmt(rpy))
        ET.SubElement(robot, "link", name=f"tip{b}")
        tip_bodies.append(index)
        tip_rot.append(rpy_matrix(rpy))
        tip_xyz.append(xyz)
        tips.append(f"tip{b}")
    f = lambda key: np.asarray(fields[key], dtype=float)
    tree = TreeRobot(
        base_mass=np.float64(base_mass),
        base_com=base_com,
        base_inertia=base_inertia,
        mount_xyz=np.zeros((1, 3)),
        mount_rpy=np.zeros((1, 3)),
        root_mass=np.zeros(1),
        root_com=np.zeros((1, 3)),
        root_inertia=np.zeros((1, 3, 3)),
        joint_rotation=f("rot"),
        joint_translation=f("xyz"),
        joint_axis=f("axis"),
        link_mass=f("mass"),
        link_com=f("com"),
        link_inertia=f("inertia"),
        tip_rotation=np.asarray(tip_rot),
        tip_translation=np.asarray(tip_xyz),
        joint_lower=f("lower"),
        joint_upper=f("upper"),
        joint_kinds=tuple(kinds),
        parents=tuple(parents),
        tip_bodies=tuple(tip_bodies),
        labels=TreeLabels(
            name=f"tree{seed}",
            joint_names=tuple(names),
            tip_names=tuple(tips),
            root_names=("bus",),
            joint_roots=(0,) * len(names),
            urdf_types=tuple(urdf_types),
        ),
    )
    return ET.tostring(robot, encoding="unicode"), tree


# Pinocchio --------------------------------------------------------------------------------


class PinocchioTree:
    """A free-flyer on ``bus`` (at the identity), joints picked in the tree's order."""

    def __init__(self, urdf_text: str, joint_names, tip_frames):
        import pinocchio as pin

        self.pin = pin
        self.model = pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
        self.data = self.model.createData()
        self.joints = [self.model.joints[self.model.getJointId(name)] for name in joint_names]
        self.columns = np.array([6 + j.idx_v - 6 for j in self.joints])
        self.frames = [self.model.getFrameId(name) for name in tip_frames]

    def config(self, q):
        return pinocchio_configuration(self.model, self.joints, q)

    def evaluate(self, q):
        """Tips about the centroid (k, 3), J* (k, 6, n), fixed-base J (k, 6, n), C (6, n) [v of bus origin; w]."""
        pin, model, data = self.pin, self.model, self.data
        config = self.config(q)
        M = pin.crba(model, data, config)
        M = np.triu(M) + np.triu(M, 1).T
        com = pin.centerOfMass(model, data, config)
        pin.computeJointJacobians(model, data, config)
        pin.updateFramePlacements(model, data)
        solve = np.linalg.solve(M[:6, :6], M[:6, 6:])
        cols = self.columns
        tips, jstar, fixed = [], [], []
        for frame in self.frames:
            J = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            tips.append(data.oMf[frame].translation - com)
            jstar.append((J[:, 6:] - J[:, :6] @ solve)[:, cols - 6])
            fixed.append(J[:, 6:][:, cols - 6])
        C = -solve[:, cols - 6]
        return {"tip": np.array(tips), "jstar": np.array(jstar), "fixed": np.array(fixed), "base": C}


def relative(J, p, i, j):
    """[Jv_j - Jv_i + [p_j - p_i]x Jw_i ; Jw_j - Jw_i] for (k, 6, n) Jacobians and (k, 3) points."""
    d = p[j] - p[i]
    lever = np.cross(d[:, None], J[i, 3:], axis=0)
    return np.concatenate([J[j, :3] - J[i, :3] + lever, J[j, 3:] - J[i, 3:]])
