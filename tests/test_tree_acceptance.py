"""Acceptance: robots written by hand as a new user would, against Pinocchio.

Three systems no other test has seen, each loaded from a robot file through
`spacearm.load_robot` (the ``system:`` form, and the ``arms:`` form for the second):

- ``SPART_STYLE``: a two-arm spacecraft written the way SPART's and SpaceDyn-derived URDFs
  are (a ``world`` link above the bus on a fixed joint with an rpy, a rigid solar panel,
  planar link inertias taken as written, a massless link with inertia, revolute joints
  without limits, axes not of unit length, end effectors on fixed joints with an rpy and
  no inertial);
- two UR5 (example-robot-data) on a 400 kg cube written as ONE URDF (the cube is
  ``base_link``, prefixed arms on fixed joints, transmissions kept), and the same robot as
  an ``arms:`` file: the two forms give the same kernels;
- ``THREE_ARM``: three arms with continuous, prismatic and skewed-axis joints, a two-finger
  gripper (one finger a URDF ``mimic``) locked in ``lock_joints`` and a camera joint held
  by ``lock_others``.

The reference puts Pinocchio's free-flyer on the URDF's root link (``world`` where there is
one), locks joints with ``pin.buildReducedModel``, places the free-flyer so the bus sits at
the wanted attitude, and computes J* = J_m - J_b M_bb^-1 M_bm per tip from ``crba`` and
LOCAL_WORLD_ALIGNED frame Jacobians. The free-flyer's velocity is the twist of the root
link's origin, so the bus-centroid twist C is formed from it (v_c = v_o + w x (c - o)).
Tips, J*, w*, the relative Jacobian, C and C_w, and the reaction null space agree to
1e-10; the bus attitude after a closed loop of all arms agrees with an RK4 integration of
Pinocchio's momentum map to 1e-8 rad.
"""

from __future__ import annotations

import functools
import importlib.util
import itertools
import xml.etree.ElementTree as ET

import jax
import numpy as np
import pytest

import spacearm as sa
from spacearm.analysis.reaction import reaction_null_space
from spacearm.cli import main
from spacearm.models.spatial import locate_package_file
from spacearm.models.spatial.urdf import rpy_matrix

from .spatial_references import pinocchio_configuration

pin = pytest.importorskip("pinocchio")

SPART_STYLE = """<!-- A two-arm spacecraft written the way SPART / SpaceDyn-derived URDFs are:
     a world link, the spacecraft on a fixed joint with an rpy, planar-ish link inertias,
     revolute joints without limits, end effectors on fixed joints with no inertial. -->
<robot name="Servicer_2Arm">
  <material name="Grey"><color rgba="0.5 0.5 0.5 1.0"/></material>
  <link name="world"/>
  <joint name="world_to_spacecraft" type="fixed">
    <parent link="world"/>
    <child link="Base_Spacecraft"/>
    <origin rpy="0.3 -0.2 0.7" xyz="1.0 -2.0 0.5"/>
  </joint>
  <link name="Base_Spacecraft">
    <inertial>
      <origin rpy="0.1 0.05 -0.3" xyz="0.02 -0.01 0.03"/>
      <mass value="120.0"/>
      <inertia ixx="14.2" ixy="0.31" ixz="-0.12" iyy="11.7" iyz="0.05" izz="9.8"/>
    </inertial>
    <visual><geometry><box size="1 1 1"/></geometry><material name="Grey"/></visual>
  </link>
  <joint name="solar_panel_joint" type="fixed">
    <parent link="Base_Spacecraft"/>
    <child link="Solar_Panel"/>
    <origin rpy="0 0 1.5707963267949" xyz="0 0.8 0"/>
  </joint>
  <link name="Solar_Panel">
    <inertial>
      <origin rpy="0 0 0" xyz="0.4 0 0"/>
      <mass value="6.0"/>
      <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.45" iyz="0" izz="0.5"/>
    </inertial>
  </link>
  <!-- Arm A: three revolute joints, no limits (SPART does not read them) -->
  <joint name="J1A" type="revolute">
    <origin rpy="0 0 0" xyz="0.5 0 0.3"/>
    <axis xyz="0 0 2"/>
    <parent link="Base_Spacecraft"/>
    <child link="L1A"/>
  </joint>
  <link name="L1A">
    <inertial>
      <origin rpy="0 1.5707963267949 0" xyz="0 0 0.1"/>
      <mass value="4.0"/>
      <inertia ixx="0.012" ixy="0.001" ixz="0" iyy="0.011" iyz="0.0005" izz="0.004"/>
    </inertial>
  </link>
  <joint name="J2A" type="revolute">
    <origin rpy="1.5707963267949 0 0" xyz="0 0 0.2"/>
    <axis xyz="0 0 1"/>
    <parent link="L1A"/>
    <child link="L2A"/>
  </joint>
  <link name="L2A">
    <inertial>
      <origin rpy="0.2 0 0.1" xyz="0.25 0 0"/>
      <mass value="5.0"/>
      <inertia ixx="0.006" ixy="0" ixz="0.0004" iyy="0.11" iyz="0" izz="0.11"/>
    </inertial>
  </link>
  <joint name="J3A" type="revolute">
    <origin rpy="0 0 0" xyz="0.5 0 0"/>
    <axis xyz="0 1 1"/>
    <parent link="L2A"/>
    <child link="L3A"/>
  </joint>
  <link name="L3A">
    <inertial>
      <origin rpy="0 0 0" xyz="0.2 0 0"/>
      <mass value="3.0"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.045" iyz="0" izz="0.045"/>
    </inertial>
  </link>
  <joint name="EE_A_joint" type="fixed">
    <origin rpy="0 1.5707963267949 0.4" xyz="0.4 0 0"/>
    <parent link="L3A"/>
    <child link="EE_A"/>
  </joint>
  <link name="EE_A"/>
  <!-- Arm B: three revolute joints, SPART-style planar inertias (ixx = iyy = 0) -->
  <joint name="J1B" type="revolute">
    <origin rpy="0 0 3.14159265358979" xyz="-0.5 0 0.3"/>
    <axis xyz="0 0 1"/>
    <parent link="Base_Spacecraft"/>
    <child link="L1B"/>
  </joint>
  <link name="L1B">
    <inertial>
      <origin rpy="0 0 0" xyz="0.1926 0 0"/>
      <mass value="2.9"/>
      <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0.1245"/>
    </inertial>
  </link>
  <joint name="J2B" type="revolute">
    <origin rpy="-1.5707963267949 0 0" xyz="0.3852 0 0"/>
    <axis xyz="0 0 -1"/>
    <parent link="L1B"/>
    <child link="L2B"/>
  </joint>
  <link name="L2B">
    <inertial>
      <origin rpy="0 0 0" xyz="0.1635 0 0"/>
      <mass value="2.9"/>
      <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0.1245"/>
    </inertial>
  </link>
  <joint name="J3B" type="continuous">
    <origin rpy="0 0 0" xyz="0.327 0 0"/>
    <axis xyz="3 0 0"/>
    <parent link="L2B"/>
    <child link="L3B"/>
  </joint>
  <link name="L3B">
    <inertial>
      <origin rpy="0 0 0" xyz="0.05 0.01 0"/>
      <mass value="0.0"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/>
    </inertial>
  </link>
  <joint name="EE_B_joint" type="fixed">
    <origin rpy="0.1 0.2 0.3" xyz="0.1 0 0.05"/>
    <parent link="L3B"/>
    <child link="EE_B"/>
  </joint>
  <link name="EE_B"/>
</robot>
"""

THREE_ARM = """<robot name="tri_servicer">
  <link name="world"/>
  <joint name="world_joint" type="fixed">
    <parent link="world"/><child link="hub"/>
    <origin xyz="0 0 1" rpy="0 0 0"/>
  </joint>
  <link name="hub">
    <inertial>
      <origin xyz="0.03 0.02 -0.05" rpy="0.2 -0.1 0.4"/>
      <mass value="250"/>
      <inertia ixx="42" ixy="-1.5" ixz="0.8" iyy="37" iyz="0.6" izz="30"/>
    </inertial>
  </link>
  <!-- arm a: continuous, revolute, prismatic -->
  <joint name="a_yaw" type="continuous">
    <parent link="hub"/><child link="a_l1"/>
    <origin xyz="0.6 0 0.2" rpy="0 1.5707963267949 0"/>
    <axis xyz="0 0 1"/>
  </joint>
  <link name="a_l1">
    <inertial><origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="6"/>
      <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.02"/></inertial>
  </link>
  <joint name="a_pitch" type="revolute">
    <parent link="a_l1"/><child link="a_l2"/>
    <origin xyz="0 0 0.2" rpy="-1.5707963267949 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2.0" upper="2.0" effort="50" velocity="1"/>
  </joint>
  <link name="a_l2">
    <inertial><origin xyz="0.3 0 0" rpy="0 0 0.1"/><mass value="8"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.25" iyz="0" izz="0.25"/></inertial>
  </link>
  <joint name="a_extend" type="prismatic">
    <parent link="a_l2"/><child link="a_l3"/>
    <origin xyz="0.6 0 0" rpy="0 0 0"/>
    <axis xyz="2 0 0"/>
    <limit lower="-0.1" upper="0.4" effort="100" velocity="0.2"/>
  </joint>
  <link name="a_l3">
    <inertial><origin xyz="0.15 0 0" rpy="0 0 0"/><mass value="3"/>
      <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.03"/></inertial>
  </link>
  <joint name="a_tool_joint" type="fixed">
    <parent link="a_l3"/><child link="a_tool"/>
    <origin xyz="0.3 0 0" rpy="0 0 0.5"/>
  </joint>
  <link name="a_tool"/>
  <!-- arm b: revolute, continuous (skewed axis), revolute -->
  <joint name="b_shoulder" type="revolute">
    <parent link="hub"/><child link="b_l1"/>
    <origin xyz="-0.3 0.52 0.2" rpy="-1.5707963267949 0 2.0943951023932"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3.0" upper="3.0" effort="50" velocity="1"/>
  </joint>
  <link name="b_l1">
    <inertial><origin xyz="0 0 0.08" rpy="0 0 0"/><mass value="5"/>
      <inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="b_elbow" type="continuous">
    <parent link="b_l1"/><child link="b_l2"/>
    <origin xyz="0 0 0.16" rpy="1.5707963267949 0 0"/>
    <axis xyz="0 0.6 0.8"/>
  </joint>
  <link name="b_l2">
    <inertial><origin xyz="0.25 0 0" rpy="0 0.3 0"/><mass value="7"/>
      <inertia ixx="0.015" ixy="0" ixz="0.002" iyy="0.16" iyz="0" izz="0.16"/></inertial>
  </link>
  <joint name="b_wrist" type="revolute">
    <parent link="b_l2"/><child link="b_l3"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/>
    <axis xyz="1 0 0"/>
    <limit lower="-2.5" upper="2.5" effort="20" velocity="1"/>
  </joint>
  <link name="b_l3">
    <inertial><origin xyz="0.05 0 0" rpy="0 0 0"/><mass value="2"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.004"/></inertial>
  </link>
  <joint name="b_tool_joint" type="fixed">
    <parent link="b_l3"/><child link="b_tool"/>
    <origin xyz="0.12 0 0" rpy="0.3 0 0"/>
  </joint>
  <link name="b_tool"/>
  <!-- arm c: prismatic boom, revolute, revolute wrist with a two-finger gripper (to lock) -->
  <joint name="c_boom" type="prismatic">
    <parent link="hub"/><child link="c_l1"/>
    <origin xyz="-0.3 -0.52 0.2" rpy="1.5707963267949 0 -2.0943951023932"/>
    <axis xyz="0 0 1"/>
    <limit lower="0.0" upper="0.5" effort="100" velocity="0.1"/>
  </joint>
  <link name="c_l1">
    <inertial><origin xyz="0 0 0.2" rpy="0 0 0"/><mass value="4"/>
      <inertia ixx="0.06" ixy="0" ixz="0" iyy="0.06" iyz="0" izz="0.005"/></inertial>
  </link>
  <joint name="c_pitch" type="revolute">
    <parent link="c_l1"/><child link="c_l2"/>
    <origin xyz="0 0 0.4" rpy="1.5707963267949 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2.0" upper="2.0" effort="50" velocity="1"/>
  </joint>
  <link name="c_l2">
    <inertial><origin xyz="0.2 0 0" rpy="0 0 0"/><mass value="5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.08" iyz="0" izz="0.08"/></inertial>
  </link>
  <joint name="c_roll" type="revolute">
    <parent link="c_l2"/><child link="c_hand"/>
    <origin xyz="0.4 0 0" rpy="0 0 0"/>
    <axis xyz="1 0 0"/>
    <limit lower="-3.0" upper="3.0" effort="20" velocity="1"/>
  </joint>
  <link name="c_hand">
    <inertial><origin xyz="0.04 0 0" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="c_finger_left_joint" type="prismatic">
    <parent link="c_hand"/><child link="c_finger_left"/>
    <origin xyz="0.08 0.01 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="0.0" upper="0.04" effort="10" velocity="0.05"/>
  </joint>
  <link name="c_finger_left">
    <inertial><origin xyz="0.02 0 0" rpy="0 0 0"/><mass value="0.2"/>
      <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/></inertial>
  </link>
  <joint name="c_finger_right_joint" type="prismatic">
    <parent link="c_hand"/><child link="c_finger_right"/>
    <origin xyz="0.08 -0.01 0" rpy="0 0 0"/>
    <axis xyz="0 -1 0"/>
    <limit lower="0.0" upper="0.04" effort="10" velocity="0.05"/>
    <mimic joint="c_finger_left_joint" multiplier="1" offset="0"/>
  </joint>
  <link name="c_finger_right">
    <inertial><origin xyz="0.02 0 0" rpy="0 0 0"/><mass value="0.2"/>
      <inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/></inertial>
  </link>
  <joint name="c_tcp_joint" type="fixed">
    <parent link="c_hand"/><child link="c_tcp"/>
    <origin xyz="0.12 0 0" rpy="0 -1.5707963267949 0"/>
  </joint>
  <link name="c_tcp"/>
  <!-- a camera pan joint on the hub, off every arm -->
  <joint name="camera_pan" type="revolute">
    <parent link="hub"/><child link="camera"/>
    <origin xyz="0 0 0.6" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="0.2" upper="1.5" effort="1" velocity="1"/>
  </joint>
  <link name="camera">
    <inertial><origin xyz="0.05 0 0" rpy="0 0 0"/><mass value="1.0"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial>
  </link>
</robot>
"""

UR5 = "robots/ur_description/urdf/ur5_robot.urdf"
UR5_MOUNTS = {
    "left": ([0.3, 0.5526, 0.08], [-np.pi / 2, 0.0, 0.1]),
    "right": ([0.3, -0.5526, 0.08], [np.pi / 2, 0.0, -0.2]),
}
CUBE_COM = [0.01, -0.02, 0.03]
CUBE_INERTIA = [[59.6, 0.4, -0.2], [0.4, 60.1, 0.3], [-0.2, 0.3, 58.9]]


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def dual_ur5_urdf(ur5_text: str) -> str:
    """Two UR5 on a cube as one URDF: ``base_link`` the cube, ``left_``/``right_`` prefixed arms."""
    ur5 = ET.fromstring(ur5_text)
    out = ET.Element("robot", name="dual_ur5_cube")
    inertial = ET.SubElement(ET.SubElement(out, "link", name="base_link"), "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(CUBE_COM), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value="400")
    I = np.array(CUBE_INERTIA)
    ET.SubElement(
        inertial,
        "inertia",
        ixx=repr(float(I[0, 0])),
        ixy=repr(float(I[0, 1])),
        ixz=repr(float(I[0, 2])),
        iyy=repr(float(I[1, 1])),
        iyz=repr(float(I[1, 2])),
        izz=repr(float(I[2, 2])),
    )
    for arm, (xyz, rpy) in UR5_MOUNTS.items():
        prefix = arm + "_"
        mount = ET.SubElement(out, "joint", name=prefix + "mount_joint", type="fixed")
        ET.SubElement(mount, "parent", link="base_link")
        ET.SubElement(mount, "child", link=prefix + "base_link")
        ET.SubElement(mount, "origin", xyz=_fmt(xyz), rpy=_fmt(rpy))
        for element in ur5:
            if element.get("name") in ("world", "world_joint") or element.tag not in ("link", "joint", "transmission"):
                continue
            copy = ET.fromstring(ET.tostring(element))
            copy.set("name", prefix + copy.get("name"))
            if element.tag == "joint":
                for tag in ("parent", "child"):
                    copy.find(tag).set("link", prefix + copy.find(tag).get("link"))
            for joint in copy.findall("joint") if element.tag == "transmission" else []:
                joint.set("name", prefix + joint.get("name"))
            out.append(copy)
    return ET.tostring(out, encoding="unicode")


# Pinocchio, free-flyer on the URDF's root link --------------------------------------------


def _hat(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


class FreeFlyer:
    """Pinocchio's free-flyer model of a whole-system URDF, evaluated with the bus at ``R``."""

    def __init__(self, urdf_text, *, bus, joint_names, tips, locked=None):
        # urdfdom refuses revolute joints without <limit> (SPART reads them as unlimited): add wide ones.
        document = ET.fromstring(urdf_text)
        for joint in document.findall("joint"):
            if joint.get("type") in ("revolute", "prismatic") and joint.find("limit") is None:
                ET.SubElement(joint, "limit", lower="-10", upper="10", effort="1", velocity="1")
        full = pin.buildModelFromXML(ET.tostring(document, encoding="unicode"), pin.JointModelFreeFlyer())
        model = full
        if locked:
            reference = pin.neutral(full)
            for name, value in locked.items():
                reference[full.joints[full.getJointId(name)].idx_q] = value
            model = pin.buildReducedModel(full, [full.getJointId(name) for name in locked], reference)
        self.model, self.data = model, model.createData()
        bus_frame = model.frames[model.getFrameId(bus)]
        assert bus_frame.parentJoint == 1  # the bus rides on the free-flyer
        self.bus_in_root = bus_frame.placement  # the bus frame in the free-flyer's body frame
        self.joints = [model.joints[model.getJointId(name)] for name in joint_names]
        self.columns = np.array([joint.idx_v - 6 for joint in self.joints])
        self.tips = [model.getFrameId(name) for name in tips]

    def config(self, q, R=None):
        R = np.eye(3) if R is None else R
        root = pin.SE3(R, np.zeros(3)) * self.bus_in_root.inverse()  # puts the bus at (R, 0)
        return pinocchio_configuration(self.model, self.joints, q, pin.SE3ToXYZQUAT(root))

    def evaluate(self, q, R=None):
        """Tips about the centroid (k, 3), J* and fixed-base J (k, 6, n), C (6, n), inertial axes."""
        model, data = self.model, self.data
        config = self.config(q, R)
        M = pin.crba(model, data, config)
        M = np.triu(M) + np.triu(M, 1).T
        com = pin.centerOfMass(model, data, config)
        pin.computeJointJacobians(model, data, config)
        pin.updateFramePlacements(model, data)
        solve = np.linalg.solve(M[:6, :6], M[:6, 6:])[:, self.columns]
        tips, jstar, fixed = [], [], []
        for frame in self.tips:
            J = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            tips.append(data.oMf[frame].translation - com)
            jstar.append(J[:, 6 + self.columns] - J[:, :6] @ solve)
            fixed.append(J[:, 6 + self.columns])
        # The free-flyer velocity is the root link's twist; the bus centroid c moves at v_o + w x (c - o).
        root = pin.getJointJacobian(model, data, 1, pin.LOCAL_WORLD_ALIGNED)[:, :6]
        twist = -root @ solve
        lever = data.oMi[1].rotation @ model.inertias[1].lever
        twist[:3] += np.cross(twist[3:].T, lever).T
        return {"tip": np.array(tips), "jstar": np.array(jstar), "fixed": np.array(fixed), "base": twist}

    def loop_attitude(self, waypoints, R0, steps=400):
        """Bus attitude after the joint polyline: RK4 of dR/dt = R [w]x, w = C_w(q) q_dot in bus axes."""
        R = np.array(R0, dtype=float)
        omega = lambda q, rate: self.evaluate(q)["base"][3:] @ rate
        for a, b in itertools.pairwise(waypoints):
            rate, h = b - a, 1.0 / steps
            for s in range(steps):
                q = a + s * h * rate
                k1 = R @ _hat(omega(q, rate))
                k2 = (R + h / 2 * k1) @ _hat(omega(q + h / 2 * rate, rate))
                k3 = (R + h / 2 * k2) @ _hat(omega(q + h / 2 * rate, rate))
                k4 = (R + h * k3) @ _hat(omega(q + h * rate, rate))
                R = R + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        u, _, vt = np.linalg.svd(R)
        return u @ vt


def _relative(J, p, i, j):
    lever = np.cross(p[j] - p[i], J[i, 3:].T).T
    return np.concatenate([J[j, :3] - J[i, :3] + lever, J[j, 3:] - J[i, 3:]])


def _angle(Ra, Rb):
    """The rotation angle between two attitudes, accurate for small angles (arccos of the trace is not)."""
    return 2 * np.arcsin(min(1.0, np.linalg.norm(np.asarray(Ra) - np.asarray(Rb)) / (2 * np.sqrt(2))))


# Robots, each loaded once ------------------------------------------------------------------


def _write(folder, name, text):
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("accept")


@pytest.fixture(scope="module")
def spart_style(folder):
    _write(folder, "spart_style.urdf", SPART_STYLE)
    path = _write(
        folder,
        "spart_style.yaml",
        "name: spart-style\nsystem:\n  urdf: spart_style.urdf\n  base_link: Base_Spacecraft\n"
        "  tips: [EE_A, EE_B]\n  inertia_as_written: true\n",
    )
    robot = sa.load_robot(path)
    return robot, FreeFlyer(SPART_STYLE, bus="Base_Spacecraft", joint_names=robot.joint_names, tips=robot.tip_names)


@pytest.fixture(scope="module")
def three_arm(folder):
    _write(folder, "three_arm.urdf", THREE_ARM)
    path = _write(
        folder,
        "three_arm.yaml",
        "name: three-arm\nsystem:\n  urdf: three_arm.urdf\n  base_link: hub\n  tips: [a_tool, b_tool, c_tcp]\n"
        "  lock_joints: {c_finger_left_joint: 0.02, c_finger_right_joint: 0.02}\n  lock_others: true\n",
    )
    robot = sa.load_robot(path)
    locked = {"c_finger_left_joint": 0.02, "c_finger_right_joint": 0.02, "camera_pan": 0.2}  # nearest limit
    return robot, FreeFlyer(THREE_ARM, bus="hub", joint_names=robot.joint_names, tips=robot.tip_names, locked=locked)


@pytest.fixture(scope="module")
def dual_ur5(folder):
    """The ``system:`` robot, its Pinocchio reference and the ``arms:`` robot."""
    if importlib.util.find_spec("cmeel") is None and not _has_ur5():
        pytest.skip("example-robot-data is not installed")
    with open(locate_package_file("test", "example-robot-data", UR5), encoding="utf-8") as handle:
        urdf = dual_ur5_urdf(handle.read())
    _write(folder, "dual_ur5.urdf", urdf)
    system = sa.load_robot(
        _write(
            folder,
            "dual_ur5_system.yaml",
            "name: dual-ur5\nsystem:\n  urdf: dual_ur5.urdf\n  base_link: base_link\n"
            "  tips: [left_tool0, right_tool0]\n",
        )
    )
    arms = "".join(
        f"  - name: {arm}\n    urdf: {{package: example-robot-data, path: {UR5}}}\n"
        f"    root_link: base_link\n    tip: tool0\n    mount: {{xyz: {list(xyz)}, rpy: {list(rpy)}}}\n"
        for arm, (xyz, rpy) in UR5_MOUNTS.items()
    )
    arms_robot = sa.load_robot(
        _write(
            folder,
            "dual_ur5_arms.yaml",
            f"name: dual-ur5-arms\nbase:\n  mass: 400\n  com: {CUBE_COM}\n  inertia: {CUBE_INERTIA}\narms:\n{arms}",
        )
    )
    return system, FreeFlyer(urdf, bus="base_link", joint_names=system.joint_names, tips=system.tip_names), arms_robot


def _has_ur5():
    try:
        locate_package_file("test", "example-robot-data", UR5)
    except Exception:
        return False
    return True


CASES = ("spart_style", "dual_ur5", "three_arm")


@pytest.fixture(scope="module", params=CASES)
def case(request):
    robot, reference = request.getfixturevalue(request.param)[:2]
    return request.param, robot, reference


def _postures(robot, count, seed):
    rng = np.random.default_rng(seed)
    lower = np.where(np.isfinite(robot.joint_lower), robot.joint_lower, -np.pi)
    upper = np.where(np.isfinite(robot.joint_upper), robot.joint_upper, np.pi)
    return rng.uniform(np.maximum(lower, -2.5), np.minimum(upper, 2.5), size=(count, robot.n_joints))


# Tests -------------------------------------------------------------------------------------


@functools.partial(jax.jit, static_argnames=("pairs",))
def _kernels_in_one_program(robot, q, R, pairs):
    """Tips, J*, w*, C, the reaction null space and the relative Jacobian of each tip pair, as
    one program: the kernels are jitted functions, inlined here unchanged, so each robot's
    structure compiles once instead of once per kernel and pair (about 40 % less CPU)."""
    return (
        sa.tip_position(robot, q, base_rotation=R),
        sa.generalized_jacobian(robot, q, base_rotation=R),
        sa.manipulability(robot, q),
        sa.base_rate_matrix(robot, q),
        reaction_null_space(robot, q),
        {pair: sa.relative_jacobian(robot, q, base_rotation=R, tips=pair) for pair in pairs},
    )


def test_kernels_match_pinocchio(case):
    """Tips, J*, w*, relative Jacobians, C and the reaction null space at random postures and
    attitudes (a few seconds per robot: each robot's kernels compile once, as one program)."""
    name, robot, reference = case
    q = _postures(robot, 4, 1)
    R = np.stack([rpy_matrix(r) for r in np.random.default_rng(2).uniform(-1.2, 1.2, size=(4, 3))])
    k, n = robot.n_tips, robot.n_joints
    pairs = tuple((i, j) for i in range(k) for j in range(i + 1, k)) + ((1, 0),)
    values = _kernels_in_one_program(robot, q, R, pairs)
    tip, J, w, C, N = (np.asarray(v) for v in values[:5])
    relative = {pair: np.asarray(v) for pair, v in values[5].items()}
    assert tip.shape == (4, k, 3) and J.shape == (4, k, 6, n) and w.shape == (4, k) and N.shape == (4, n, n - 3)
    for b in range(4):
        at_R, at_bus = reference.evaluate(q[b], R[b]), reference.evaluate(q[b])
        np.testing.assert_allclose(tip[b], at_R["tip"], atol=1e-10, err_msg=name)
        np.testing.assert_allclose(J[b], at_R["jstar"], atol=1e-10, err_msg=name)
        Jv = at_bus["jstar"][:, :3]
        np.testing.assert_allclose(w[b], np.sqrt(np.linalg.det(Jv @ np.swapaxes(Jv, -1, -2))), atol=1e-10)
        np.testing.assert_allclose(C[b], at_bus["base"], atol=1e-10, err_msg=name)
        # The reaction null space: the same subspace as the kernel of Pinocchio's C_w.
        _, _, vt = np.linalg.svd(at_bus["base"][3:])
        np.testing.assert_allclose(N[b] @ N[b].T, vt[3:].T @ vt[3:], atol=1e-10, err_msg=name)
        for (i, j), Jr in relative.items():
            np.testing.assert_allclose(Jr[b], _relative(at_R["jstar"], at_R["tip"], i, j), atol=1e-10, err_msg=name)
            # The bus drops out: the fixed-base relative Jacobian is the same.
            np.testing.assert_allclose(Jr[b], _relative(at_R["fixed"], at_R["tip"], i, j), atol=1e-10, err_msg=name)


def test_loop_of_all_arms_turns_the_bus_as_pinocchio(case):
    """A closed joint loop moving every joint of every arm: the bus attitude to 1e-8 rad (RK4 reference, ~1 s)."""
    name, robot, reference = case
    q0 = _postures(robot, 1, 3)[0]
    rng = np.random.default_rng(4)
    span = np.where(np.asarray(robot.joint_kinds) == "prismatic", 0.05, 0.6)
    d1, d2 = rng.uniform(-1, 1, size=(2, robot.n_joints)) * span
    waypoints = np.stack([q0, q0 + d1, q0 + d1 + d2, q0 + d2, q0])
    R0 = rpy_matrix([0.3, -0.4, 0.5])
    R_end, q_end = sa.integrate_joint_path(robot, q0, waypoints, base_rotation=R0)
    np.testing.assert_allclose(q_end, q0, atol=1e-12)
    expected = reference.loop_attitude(waypoints, R0, steps=60)
    turn = _angle(R0, expected)
    assert turn > 1e-4, f"{name}: the loop should turn the bus ({turn} rad)"
    assert _angle(np.asarray(R_end), expected) < 1e-8, name


def test_arms_file_and_system_file_give_the_same_kernels(dual_ur5):
    """Two UR5 on a cube as one URDF (``system:``) and as an ``arms:`` file: same joints, tips and
    numbers (several seconds: the ``arms:`` robot's kernels compile once more)."""
    system, _, arms = dual_ur5
    assert [name.replace("/", "_") for name in arms.joint_names] == list(system.joint_names)
    assert [name.replace("/", "_") for name in arms.tip_names] == list(system.tip_names)
    q = _postures(system, 8, 5)
    R = rpy_matrix([0.2, 0.1, -0.3])
    for kernel in (sa.tip_position, sa.generalized_jacobian):
        np.testing.assert_allclose(kernel(arms, q, base_rotation=R), kernel(system, q, base_rotation=R), atol=1e-12)
    # C: the same bus rotation; the translational rows are the velocity of each form's bus
    # centroid, which differ: an ``arms:`` file's bus is its ``base:`` body (the arms' root
    # links are arm bodies), a ``system:`` file's bus is base_link with every link rigidly
    # attached to it (the root links included). Moved to the bus-frame origin they agree.
    C_arms, C_system = np.asarray(sa.base_rate_matrix(arms, q)), np.asarray(sa.base_rate_matrix(system, q))
    np.testing.assert_allclose(C_arms[:, 3:], C_system[:, 3:], atol=1e-12)
    at_origin = lambda C, com: C[:, :3] - np.cross(C[:, 3:], np.asarray(com)[:, None], axisa=1, axisb=0, axisc=1)
    np.testing.assert_allclose(at_origin(C_arms, arms.base_com), at_origin(C_system, system.base_com), atol=1e-12)
    assert np.abs(C_arms[:, :3] - C_system[:, :3]).max() > 1e-5
    for kernel in (sa.manipulability, reaction_null_space):
        a, s = np.asarray(kernel(arms, q)), np.asarray(kernel(system, q))
        if kernel is reaction_null_space:
            a, s = a @ np.swapaxes(a, -1, -2), s @ np.swapaxes(s, -1, -2)
        np.testing.assert_allclose(a, s, atol=1e-12)
    np.testing.assert_allclose(
        sa.relative_jacobian(arms, q, tips=(0, 1)), sa.relative_jacobian(system, q, tips=(0, 1)), atol=1e-12
    )


def test_messages_name_tips_and_joints_of_a_system_file(three_arm):
    """A ``system:`` file has no arm names (its one root is the bus): an unknown ``moving`` entry
    lists tips and joints, not the bus as an arm; a start outside a limit names the joint."""
    robot, _ = three_arm
    with pytest.raises(sa.ConfigError) as error:
        robot.focus(tip="c_tcp", moving="arm_c")
    message = str(error.value)
    assert "the arms are" not in message
    assert "the tips are a_tool, b_tool, c_tcp; the joints are a_yaw, a_pitch" in message
    q = np.zeros(robot.n_joints)
    q[robot.joint_names.index("c_boom")] = 0.9
    with pytest.raises(sa.ConfigError, match=r"joint 7 = 0.9 is outside its limits \[0, 0.5\] \(c_boom\)"):
        sa.plan_reach(robot.focus(tip="c_tcp"), q, [-1.2, -0.45, 0.3])


def test_lock_others_holds_a_mimic_finger_where_its_leader_puts_it(folder):
    """Lock one finger of the three-arm system's gripper; ``lock_others`` holds the ``<mimic>``
    finger at multiplier * leader + offset (here 0.02), the camera at its nearest limit: the
    bus and the hand weigh as with both fingers locked at 0.02 by hand."""
    common = "name: t\nsystem:\n  urdf: three_arm.urdf\n  base_link: hub\n  tips: [a_tool, b_tool, c_tcp]\n"
    _write(folder, "three_arm.urdf", THREE_ARM)
    by_hand = sa.load_robot(
        _write(
            folder,
            "by_hand.yaml",
            common + "  lock_joints: {c_finger_left_joint: 0.02, c_finger_right_joint: 0.02, camera_pan: 0.2}\n",
        )
    )
    mimic = sa.load_robot(
        _write(folder, "mimic.yaml", common + "  lock_joints: {c_finger_left_joint: 0.02}\n  lock_others: true\n")
    )
    for field in ("base_com", "base_inertia", "link_com", "link_inertia"):
        np.testing.assert_allclose(getattr(mimic, field), getattr(by_hand, field), atol=1e-15, err_msg=field)
    # Held at 0 instead, the hand's centroid would be 0.2 * 0.02 / 1.9 = 2.1 mm off in y.
    far = sa.load_robot(
        _write(
            folder,
            "far.yaml",
            common + "  lock_joints: {c_finger_left_joint: 0.02, c_finger_right_joint: 0}\n  lock_others: true\n",
        )
    )
    assert abs(far.link_com[-1][1] - by_hand.link_com[-1][1]) > 2e-3


def test_validate_names_each_system(three_arm, spart_style, folder, capsys):
    """``spacearm validate`` on the hand-written files: joints and tips counted as loaded."""
    assert main(["validate", str(folder / "three_arm.yaml")]) == 0
    assert main(["validate", str(folder / "spart_style.yaml")]) == 0
    out = capsys.readouterr().out
    assert "valid robot (three-arm, 9 joints, tips a_tool, b_tool, c_tcp)" in out
    assert "valid robot (spart-style, 6 joints, tips EE_A, EE_B)" in out


@pytest.mark.slow  # compiles the straight-path and loop programs of the 9-joint tree (tens of seconds)
def test_reach_with_a_chosen_tip_lands_where_pinocchio_says(three_arm, folder, capsys):
    """``spacearm reach --tip c_tcp``: the last posture and bus attitude of reach.npz put Pinocchio's
    c_tcp on the target (the bus turns first: a reorientation loop, then the straight path)."""
    _, reference = three_arm
    out = folder / "reach"
    start = "--from=10,20,0.1,30,40,-20,0.2,30,10"
    assert (
        main(
            ["reach", str(folder / "three_arm.yaml"), start, "--to=-1.2,-0.45,0.3", "--tip", "c_tcp", "--out", str(out)]
        )
        == 0
    )
    history = np.load(out / "reach.npz")
    assert int(history["tip_index"]) == 2
    at_end = reference.evaluate(history["joints"][-1], history["base_rotation"][-1])
    np.testing.assert_allclose(at_end["tip"][2], [-1.2, -0.45, 0.3], atol=1e-9)
    if "loop_waypoints" in history:
        expected = reference.loop_attitude(history["loop_waypoints"], np.eye(3), steps=40)
        assert _angle(expected, history["loop_rotation"]) < 1e-8


def test_pose_targets_need_six_joints_on_the_tips_own_path(three_arm):
    """Tip a_tool has 3 joints on its path; the 6 others move it only through the bus (J* has
    rank 6 over all 9, at impractical rates): a pose target is refused up front, naming why."""
    robot, _ = three_arm
    focused = robot.focus(tip="a_tool")
    q = np.zeros(robot.n_joints)
    q[robot.joint_names.index("c_boom")] = 0.2
    with pytest.raises(sa.ConfigError, match=r"the tip's path from the bus has 3 moving \(the other arms"):
        sa.plan_pose_reach(focused, q, [0.5, 0.1, -0.6], np.eye(3))
