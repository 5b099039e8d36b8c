"""Independent references for the spatial family: Pinocchio, iDynTree, MuJoCo.

Each reference reads the arm through its own URDF parser. The bus, the mount and
locked joints are written into one URDF (:func:`combined_urdf`): a ``bus`` link with
the bus inertial, a fixed ``mount`` joint to the arm's root link (origin = mount pose),
the arm below the root link, locked joints turned into fixed joints at their value,
geometry stripped. The references then put a free-floating joint on ``bus``; bus pose =
identity, so world axes are bus axes. J* = J_m - J_b H_b^-1 H_bm does not depend on
how each library parametrizes the base velocity (SPATIAL.md).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import yaml

from spacearm._core.groups import rpy_matrix
from spacearm.models.spatial import locate_package_file


def matrix_rpy(rotation: np.ndarray) -> np.ndarray:
    """URDF rpy of a rotation matrix (inverse of rpy_matrix away from pitch = +-pi/2)."""
    pitch = math.asin(-max(-1.0, min(1.0, rotation[2, 0])))
    roll = math.atan2(rotation[2, 1], rotation[2, 2])
    yaw = math.atan2(rotation[1, 0], rotation[0, 0])
    return np.array([roll, pitch, yaw])


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def combined_urdf(
    urdf_text: str,
    *,
    root_link: str,
    base_mass: float,
    base_com,
    base_inertia,
    mount_xyz,
    mount_rpy,
    lock_joints=None,
) -> str:
    """One URDF: bus + fixed mount joint + the arm below root_link (locked joints fixed)."""
    lock_joints = dict(lock_joints or {})
    tree = ET.fromstring(urdf_text)
    links = {e.get("name"): e for e in tree.findall("link")}
    joints = tree.findall("joint")
    children: dict[str, list] = {}
    for j in joints:
        children.setdefault(j.find("parent").get("link"), []).append(j)
    keep_links, keep_joints, stack = {root_link}, [], [root_link]
    while stack:
        name = stack.pop()
        for j in children.get(name, []):
            keep_joints.append(j)
            child = j.find("child").get("link")
            keep_links.add(child)
            stack.append(child)
    robot = ET.Element("robot", name="combined")
    bus = ET.SubElement(robot, "link", name="bus")
    inertial = ET.SubElement(bus, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(base_com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(base_mass)))
    I = np.asarray(base_inertia, dtype=float)
    ET.SubElement(
        inertial,
        "inertia",
        **{
            k: repr(float(I[i, j]))
            for k, (i, j) in zip(
                ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)),
                strict=False,
            )
        },
    )
    mount = ET.SubElement(robot, "joint", name="mount", type="fixed")
    ET.SubElement(mount, "origin", xyz=_fmt(mount_xyz), rpy=_fmt(mount_rpy))
    ET.SubElement(mount, "parent", link="bus")
    ET.SubElement(mount, "child", link=root_link)
    for name in sorted(keep_links):
        link = ET.fromstring(ET.tostring(links[name]))
        for tag in ("visual", "collision"):
            for e in link.findall(tag):
                link.remove(e)
        robot.append(link)
    for j in keep_joints:
        j = ET.fromstring(ET.tostring(j))
        for tag in ("dynamics", "safety_controller", "calibration", "mimic"):
            for e in j.findall(tag):
                j.remove(e)
        name = j.get("name")
        if name in lock_joints:
            value = float(lock_joints[name])
            origin = j.find("origin")
            xyz = np.array([float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()])
            rpy = np.array([float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()])
            axis_e = j.find("axis")
            axis = (
                np.array([float(v) for v in axis_e.get("xyz").split()]) if axis_e is not None else np.array([1.0, 0, 0])
            )
            axis = axis / np.linalg.norm(axis)
            rot = rpy_matrix(rpy)
            if j.get("type") == "prismatic":
                xyz = xyz + rot @ axis * value
            else:
                k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
                rot = rot @ (np.eye(3) + math.sin(value) * k + (1 - math.cos(value)) * k @ k)
            for e in list(j):
                if e.tag in ("origin", "axis", "limit"):
                    j.remove(e)
            j.set("type", "fixed")
            ET.SubElement(j, "origin", xyz=_fmt(xyz), rpy=_fmt(matrix_rpy(rot)))
        robot.append(j)
    return ET.tostring(robot, encoding="unicode")


def config_urdf(path) -> tuple[str, np.ndarray]:
    """The :func:`combined_urdf` of a one-arm robot file (e.g. configs/ur5-smallsat.yaml), its
    bus and mount read from the file, and the bus centroid ``base.com`` (3,) m, bus frame.

    Only an arm whose ``urdf`` names a package file (``{package, path}``), as the shipped
    files do."""
    config = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    base, mount, arm = config["base"], config["mount"], config["arm"]
    urdf = locate_package_file(str(path), arm["urdf"]["package"], arm["urdf"]["path"])
    text = combined_urdf(
        Path(urdf).read_text(encoding="utf-8"),
        root_link=arm["root_link"],
        base_mass=base["mass"],
        base_com=base["com"],
        base_inertia=base["inertia"],
        mount_xyz=mount["xyz"],
        mount_rpy=mount["rpy"],
        lock_joints=arm.get("lock_joints"),
    )
    return text, np.asarray(base["com"], dtype=float)


def pinocchio_configuration(model, joints, q, root=None) -> np.ndarray:
    """Pinocchio's configuration vector (model.nq,) of a free-flyer ``model``: the free-flyer
    at ``root`` ((7,): position, then quaternion coefficients (x, y, z, w); the identity when
    None) and each of ``joints`` (Pinocchio joint models) at its entry of ``q`` (rad or m), a
    continuous joint written as (cos, sin)."""
    import pinocchio as pin

    config = pin.neutral(model)
    if root is not None:
        config[:7] = root
    for joint, value in zip(joints, q, strict=True):
        if joint.nq == 2:  # continuous: (cos, sin)
            config[joint.idx_q : joint.idx_q + 2] = np.cos(value), np.sin(value)
        else:
            config[joint.idx_q] = value
    return config


def _jstar(J, M):
    return J[:, 6:] - J[:, :6] @ np.linalg.solve(M[:6, :6], M[:6, 6:])


def _hstar(M):
    return M[6:, 6:] - M[6:, :6] @ np.linalg.solve(M[:6, :6], M[:6, 6:])


# Pinocchio ----------------------------------------------------------------------------


def pinocchio_reference(combined: str, joint_names, tip: str, q):
    """J*, tip about the centroid, H_m, H*, and C(q) in [v bus centroid; w] from Pinocchio."""
    import pinocchio as pin

    model = pin.buildModelFromXML(combined, pin.JointModelFreeFlyer())
    data = model.createData()
    config = pin.neutral(model)  # bus at the origin, identity attitude
    velocity_index = []
    for name, value in zip(joint_names, q, strict=False):
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 2:  # continuous: (cos, sin)
            config[joint.idx_q : joint.idx_q + 2] = [math.cos(value), math.sin(value)]
        else:
            config[joint.idx_q] = value
        velocity_index.append(joint.idx_v)
    order = list(range(6)) + velocity_index
    M = pin.crba(model, data, config)
    M = np.triu(M) + np.triu(M, 1).T
    M = M[np.ix_(order, order)]
    frame = model.getFrameId(tip, pin.BODY)
    J = pin.computeFrameJacobian(model, data, config, frame, pin.LOCAL_WORLD_ALIGNED)[:, order]
    pin.framesForwardKinematics(model, data, config)
    com = pin.centerOfMass(model, data, config)
    tip_about_com = data.oMf[frame].translation - com
    return {
        "jstar": _jstar(J, M),
        "tip": tip_about_com,
        "fixed": J[:, 6:],
        "mass_matrix": M[6:, 6:],
        "arm_inertia": _hstar(M),
        "free_flyer_rate": -np.linalg.solve(M[:6, :6], M[:6, 6:]),  # [v of bus origin; w], bus axes
    }


# iDynTree (MIXED) ---------------------------------------------------------------------


def idyntree_reference(combined: str, joint_names, tip: str, q):
    import idyntree.bindings as idt

    loader = idt.ModelLoader()
    assert loader.loadReducedModelFromString(combined, list(joint_names)), "iDynTree could not load the URDF"
    kin = idt.KinDynComputations()
    assert kin.loadRobotModel(loader.model())
    kin.setFloatingBase("bus")
    kin.setFrameVelocityRepresentation(idt.MIXED_REPRESENTATION)
    n = len(joint_names)
    s = idt.VectorDynSize(n)
    for i, value in enumerate(q):
        s.setVal(i, float(value))
    ds = idt.VectorDynSize(n)
    ds.zero()
    gravity = idt.Vector3()
    gravity.zero()
    kin.setRobotState(idt.Transform.Identity(), s, idt.Twist.Zero(), ds, gravity)
    M = idt.MatrixDynSize(6 + n, 6 + n)
    kin.getFreeFloatingMassMatrix(M)
    J = idt.MatrixDynSize(6, 6 + n)
    kin.getFrameFreeFloatingJacobian(tip, J)
    M, J = M.toNumPy(), J.toNumPy()
    transform = kin.getWorldTransform(tip)  # keep the owners alive while reading
    position = transform.getPosition()
    tip_position = np.array([position.getVal(i) for i in range(3)])
    centroid = kin.getCenterOfMassPosition()
    com = np.array([centroid.getVal(i) for i in range(3)])
    return {"jstar": _jstar(J, M), "tip": tip_position - com, "arm_inertia": _hstar(M)}


# MuJoCo -------------------------------------------------------------------------------


def mujoco_model(combined: str):
    """MuJoCo's own URDF parser on the combined file, with a free joint added to ``bus``.

    Static bodies are kept (``fusestatic`` off) so the tip frame survives; rotor
    armature, damping, friction and joint limits are cleared (the URDF has none of them).
    """
    import mujoco

    spec = mujoco.MjSpec.from_string(combined)
    spec.compiler.fusestatic = False
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.body("bus").add_freejoint()
    model = spec.compile()
    model.dof_damping[:] = 0.0
    model.dof_armature[:] = 0.0
    model.dof_frictionloss[:] = 0.0
    model.jnt_limited[:] = 0
    return model


def mujoco_reference(model, joint_names, tip: str, q):
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0  # bus at the origin, identity attitude
    columns = []
    for name, value in zip(joint_names, q, strict=False):
        joint = model.joint(name)
        data.qpos[model.jnt_qposadr[joint.id]] = value
        columns.append(model.jnt_dofadr[joint.id])
    order = list(range(6)) + columns
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    M = M[np.ix_(order, order)]
    body = model.body(tip).id
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_jacBody(model, data, jacp, jacr, body)
    J = np.vstack([jacp, jacr])[:, order]
    com = data.subtree_com[model.body("bus").id]
    return {"jstar": _jstar(J, M), "tip": data.xpos[body] - com}


# Random URDF chains -------------------------------------------------------------------


def random_rotation(rng):
    """A rotation matrix (3, 3) from a uniform random unit quaternion (w, x, y, z): four normal
    draws of ``rng``, normalized."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _inertial(rng, mass):
    sides = rng.uniform(0.05, 0.6, 3)
    principal = (
        mass
        / 12.0
        * np.array([sides[1] ** 2 + sides[2] ** 2, sides[0] ** 2 + sides[2] ** 2, sides[0] ** 2 + sides[1] ** 2])
    )
    R = random_rotation(rng)
    I = R @ np.diag(principal) @ R.T  # off-diagonal terms; the inertial rpy turns it again
    return (
        f'<inertial><origin xyz="{_fmt(rng.uniform(-0.2, 0.2, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
        f'<mass value="{float(mass)!r}"/>'
        f'<inertia ixx="{float(I[0, 0])!r}" ixy="{float(I[0, 1])!r}" ixz="{float(I[0, 2])!r}" iyy="{float(I[1, 1])!r}" iyz="{float(I[1, 2])!r}" izz="{float(I[2, 2])!r}"/>'
        "</inertial>"
    )


def random_chain_urdf(rng, n: int, kinds=None):
    """A random serial arm with every feature the reader merges.

    Revolute, continuous and prismatic joints with random (unit) axes and origins;
    off-diagonal link inertias with rotated inertial frames; a ``world`` link above
    the root (dropped); a massive root link; a fixed joint on the path; fixed side
    branches with mass (a camera on a link, a box on the root); a locked revolute side
    branch (a finger, locked at 0.4 rad); the tip a massless fixed frame.

    Returns:
        (urdf text, joint names in path order, lock_joints, tip link name)
    """
    kinds = kinds or [("revolute", "continuous", "prismatic")[i % 3] for i in range(n)]
    parts = [
        '<robot name="random">',
        '<link name="world"/>',
        '<joint name="world_joint" type="fixed"><parent link="world"/><child link="root"/></joint>',
        f'<link name="root">{_inertial(rng, 3.0)}</link>',
        f'<link name="root_box">{_inertial(rng, 1.5)}</link>',
        (
            f'<joint name="root_box_joint" type="fixed"><origin xyz="{_fmt(rng.uniform(-0.3, 0.3, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
            '<parent link="root"/><child link="root_box"/></joint>'
        ),
    ]
    parent, names = "root", []
    for i in range(n):
        kind = kinds[i]
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        limit = '<limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>' if kind != "continuous" else ""
        name = f"j{i}"
        names.append(name)
        parts.append(
            f'<joint name="{name}" type="{kind}"><origin xyz="{_fmt(rng.uniform(-0.5, 0.5, 3))}" rpy="{_fmt(rng.uniform(-np.pi, np.pi, 3))}"/>'
            f'<parent link="{parent}"/><child link="l{i}"/><axis xyz="{_fmt(axis)}"/>{limit}</joint>'
        )
        parts.append(f'<link name="l{i}">{_inertial(rng, float(rng.uniform(1.0, 10.0)))}</link>')
        parent = f"l{i}"
        if i == n // 2:  # a fixed joint on the path: l{i} -> l{i}_flange -> next joint
            parts.append(f'<link name="l{i}_flange">{_inertial(rng, 0.7)}</link>')
            parts.append(
                f'<joint name="l{i}_flange_joint" type="fixed"><origin xyz="{_fmt(rng.uniform(-0.2, 0.2, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
                f'<parent link="l{i}"/><child link="l{i}_flange"/></joint>'
            )
            parent = f"l{i}_flange"
        if i == 1:  # a camera on a fixed side branch
            parts.append(f'<link name="camera">{_inertial(rng, 0.9)}</link>')
            parts.append(
                f'<joint name="camera_joint" type="fixed"><origin xyz="{_fmt(rng.uniform(-0.2, 0.2, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
                f'<parent link="l{i}"/><child link="camera"/></joint>'
            )
    # A finger on the last link, locked, and the tip frame.
    parts.append(f'<link name="finger">{_inertial(rng, 0.4)}</link>')
    parts.append(
        f'<joint name="finger_joint" type="revolute"><origin xyz="{_fmt(rng.uniform(-0.1, 0.1, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
        f'<parent link="{parent}"/><child link="finger"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )
    parts.append('<link name="tool"/>')
    parts.append(
        f'<joint name="tool_joint" type="fixed"><origin xyz="{_fmt(rng.uniform(-0.3, 0.3, 3))}" rpy="{_fmt(rng.uniform(-1, 1, 3))}"/>'
        f'<parent link="{parent}"/><child link="tool"/></joint>'
    )
    parts.append("</robot>")
    return "\n".join(parts), names, {"finger_joint": 0.4}, "tool"
