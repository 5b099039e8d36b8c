"""The URDF reader and the spatial robot file: merging, and one clear message per bad input."""

import os

import numpy as np
import pytest

import spacearm as sa
from spacearm.models import spatial
from spacearm.models.spatial.urdf import parse_urdf

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")

INERTIAL = '<inertial><origin xyz="0.1 0 0"/><mass value="{m}"/><inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>'


def _urdf(extra_links="", extra_joints="", j1_type="revolute", axis="0 0 1", mass=2.0, inertia=0.1):
    return f"""<robot name="t">
  <link name="base">{INERTIAL.format(m=1.0, i=0.01)}</link>
  <link name="l1">{INERTIAL.format(m=mass, i=inertia)}</link>
  <link name="l2">{INERTIAL.format(m=1.0, i=0.05)}</link>
  <link name="tool"/>
  {extra_links}
  <joint name="j1" type="{j1_type}"><origin xyz="0 0 0.1"/><parent link="base"/><child link="l1"/><axis xyz="{axis}"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><origin xyz="0.5 0 0"/><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/></joint>
  <joint name="tool_joint" type="fixed"><origin xyz="0.4 0 0" rpy="0 0.3 0"/><parent link="l2"/><child link="tool"/></joint>
  {extra_joints}
  <transmission name="t1"><joint name="j1"><hardwareInterface>x</hardwareInterface></joint></transmission>
</robot>"""


def _read(text, **kwargs):
    kwargs.setdefault("root_link", "base")
    kwargs.setdefault("tip", "tool")
    return parse_urdf(text, source="arm.urdf", **kwargs)


def test_reads_the_chain_and_ignores_transmissions():
    chain = _read(_urdf())
    assert chain.joint_names == ("j1", "j2")
    assert chain.urdf_types == ("revolute", "continuous")
    assert chain.joint_lower[0] == -1 and np.isinf(chain.joint_upper[1])
    np.testing.assert_allclose(chain.tip_translation, [0.4, 0, 0])
    assert chain.body_links[2] == ("l2", "tool")


def test_fixed_and_locked_side_branches_are_merged_with_their_spatial_inertia():
    links = f'<link name="camera">{INERTIAL.format(m=3.0, i=0.02)}</link><link name="finger">{INERTIAL.format(m=0.5, i=0.001)}</link>'
    joints = (
        '<joint name="camera_joint" type="fixed"><origin xyz="0 0.2 0" rpy="0.5 0 0"/><parent link="l1"/><child link="camera"/></joint>'
        '<joint name="finger_joint" type="prismatic"><origin xyz="0 0 0.3"/><parent link="l1"/><child link="finger"/><axis xyz="1 0 0"/>'
        '<limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>'
    )
    chain = _read(_urdf(links, joints), lock_joints={"finger_joint": 0.05})
    assert set(chain.body_links[1]) == {"l1", "camera", "finger"}
    # mass and first moment add up: l1 com (0.1, 0, 0), camera (0.1, 0.2, 0) turned, finger (0.1 + 0.05, 0, 0.3)
    assert chain.body_mass[1] == pytest.approx(5.5)
    expected = (2.0 * np.array([0.1, 0, 0]) + 3.0 * np.array([0.1, 0.2, 0]) + 0.5 * np.array([0.15, 0, 0.3])) / 5.5
    np.testing.assert_allclose(chain.body_com[1], expected, atol=1e-15)

    # inertia about the merged centroid: parallel-axis sums (all three are isotropic tensors)
    def about(m, i, c):
        d = c - expected
        return i * np.eye(3) + m * (d @ d * np.eye(3) - np.outer(d, d))

    total = (
        about(2.0, 0.1, np.array([0.1, 0, 0]))
        + about(3.0, 0.02, np.array([0.1, 0.2, 0]))
        + about(0.5, 0.001, np.array([0.15, 0, 0.3]))
    )
    np.testing.assert_allclose(chain.body_inertia[1], total, atol=1e-14)


def test_zero_mass_links_are_taken_as_written():
    text = _urdf().replace(INERTIAL.format(m=1.0, i=0.01), INERTIAL.format(m=0.0, i=0.3), 1)
    chain = _read(text)
    assert chain.body_mass[0] == 0.0
    np.testing.assert_allclose(chain.body_inertia[0], 0.3 * np.eye(3))


def test_links_above_the_root_are_dropped():
    text = _urdf(
        '<link name="world"/>', '<joint name="w" type="fixed"><parent link="world"/><child link="base"/></joint>'
    )
    assert _read(text).body_links[0] == ("base",)


def test_the_triangle_inequality_opt_in():
    bad = _urdf().replace(
        INERTIAL.format(m=2.0, i=0.1),
        '<inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.5" ixy="0" ixz="0" iyz="0"/></inertial>',
    )
    with pytest.raises(
        sa.ConfigError,
        match=r"arm.urdf: link 'l1': inertial inertia: violates the triangle inequality.*0\.1, 0\.1, 0\.5",
    ):
        _read(bad)
    assert _read(bad, inertia_as_written=True).body_mass[1] == 2.0


BAD_URDFS = {
    "negative mass": (_urdf(mass=-1.0), r"arm.urdf: link 'l1': inertial mass: must not be negative"),
    "not positive definite": (_urdf(inertia=-0.1), r"arm.urdf: link 'l1': inertial inertia: must be positive definite"),
    "non-finite": (
        _urdf().replace('xyz="0.5 0 0"', 'xyz="0.5 nan 0"'),
        r"arm.urdf: joint 'j2': origin xyz: must be finite",
    ),
    "zero axis": (_urdf(axis="0 0 0"), r"arm.urdf: joint 'j1': axis xyz: must not be zero"),
    "floating": (_urdf(j1_type="floating"), r"arm.urdf: joint 'j1': type 'floating' is not supported"),
    "planar": (_urdf(j1_type="planar"), r"arm.urdf: joint 'j1': type 'planar' is not supported"),
    "unknown type": (
        _urdf(j1_type="revolut"),
        r"arm.urdf: joint 'j1': unknown type 'revolut' \(did you mean 'revolute'\?\)",
    ),
    "missing parent": (
        _urdf().replace('<parent link="l1"/><child link="l2"/>', '<parent link="l7"/><child link="l2"/>'),
        r"arm.urdf: joint 'j2': parent link 'l7' is not defined",
    ),
    "missing child": (
        _urdf().replace('<child link="tool"/>', '<child link="tol"/>'),
        r"arm.urdf: joint 'tool_joint': child link 'tol' is not defined \(did you mean 'tool'\?\)",
    ),
    "malformed": (_urdf()[:-20], r"arm.urdf: malformed XML at line \d+, column \d+"),
    "bad number": (
        _urdf().replace('xyz="0.5 0 0"', 'xyz="0.5 zero 0"'),
        r"arm.urdf: joint 'j2': origin xyz: expected 3 numbers",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_URDFS))
def test_bad_urdfs_get_one_message_naming_file_and_element(case):
    text, message = BAD_URDFS[case]
    with pytest.raises(sa.ConfigError, match=message):
        _read(text)


def test_missing_root_tip_and_unlocked_side_joints():
    with pytest.raises(
        sa.ConfigError, match=r"arm.urdf: root_link: link 'bas' is not in the URDF \(did you mean 'base'\?\)"
    ):
        _read(_urdf(), root_link="bas")
    with pytest.raises(sa.ConfigError, match=r"arm.urdf: tip: link 'hand' is not in the URDF"):
        _read(_urdf(), tip="hand")
    with pytest.raises(sa.ConfigError, match=r"tip: link 'base' is not below root_link 'l1'"):
        _read(_urdf(), root_link="l1", tip="base")
    side = _urdf(
        f'<link name="finger">{INERTIAL.format(m=0.5, i=0.001)}</link>',
        '<joint name="finger_joint" type="revolute"><parent link="l2"/><child link="finger"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>',
    )
    with pytest.raises(
        sa.ConfigError,
        match=r"joint 'finger_joint' \(revolute\) is off the path .* not locked; add it to arm.lock_joints",
    ):
        _read(side)
    with pytest.raises(
        sa.ConfigError, match=r"lock_joints: unknown joint 'fingerjoint' \(did you mean 'finger_joint'\?\)"
    ):
        _read(side, lock_joints={"fingerjoint": 0.0})
    # locking a joint on the path merges it too
    assert _read(side, lock_joints={"finger_joint": 0.1, "j2": 0.3}).joint_names == ("j1",)


# The robot file -------------------------------------------------------------------------


def _file(tmp_path, urdf_text=None, **changes):
    (tmp_path / "arm.urdf").write_text(urdf_text or _urdf())
    config = {
        "name": "t",
        "base": {"mass": 100.0, "com": [0, 0, 0], "inertia": [[10, 0, 0], [0, 10, 0], [0, 0, 10]]},
        "mount": {"xyz": [0.5, 0, 0], "rpy": [0, 0, 0]},
        "arm": {"urdf": "arm.urdf", "root_link": "base", "tip": "tool"},
    }
    for key, value in changes.items():
        section, _, field = key.partition("__")
        if field:
            config[section][field] = value
        else:
            config[section] = value
    path = tmp_path / "robot.yaml"
    import yaml

    path.write_text(yaml.safe_dump(config))
    return str(path)


def test_robot_file_loads_through_load_robot(tmp_path):
    robot = sa.load_robot(_file(tmp_path))
    assert isinstance(robot, spatial.SpatialRobot) and robot.n_joints == 2 and robot.name == "t"
    assert spatial.is_spatial_config({"arm": {}}) and not spatial.is_spatial_config({"links": []})


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"arm__tipp": "x"}, r"robot.yaml: arm: unknown key 'tipp' \(did you mean 'tip'\?\)"),
        ({"base__mas": 1.0}, r"robot.yaml: base: unknown key 'mas' \(did you mean 'mass'\?\)"),
        ({"mount__rpyy": [0, 0, 0]}, r"robot.yaml: mount: unknown key 'rpyy' \(did you mean 'rpy'\?\)"),
        (
            {"base__inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 3]]},
            r"robot.yaml: base.inertia: violates the triangle inequality",
        ),
        ({"base__inertia": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}, r"robot.yaml: base.inertia: must be symmetric"),
        ({"base__mass": -5.0}, r"robot.yaml: base.mass: must be positive"),
        ({"base__com": [0, 0]}, r"robot.yaml: base.com: must be numbers of shape \[3\]"),
        ({"arm__urdf": "nowhere.urdf"}, r"nowhere.urdf: no such URDF file"),
        (
            {"arm__urdf": {"package": "no-such-package-xyz", "path": "a.urdf"}},
            r"robot.yaml: arm.urdf.package: 'no-such-package-xyz' is not installed",
        ),
        ({"arm__lock_joints": {"jj": 0.0}}, r"robot.yaml: arm.lock_joints: \(in .*arm.urdf\) unknown joint 'jj'"),
        ({"arm__inertia_as_written": "yes"}, r"robot.yaml: arm.inertia_as_written: must be true or false"),
    ],
)
def test_robot_file_errors_name_the_file_and_field(tmp_path, changes, message):
    with pytest.raises(sa.ConfigError, match=message):
        sa.load_robot(_file(tmp_path, **changes))


def test_package_urdfs_are_located_through_importlib_metadata():
    try:
        path = spatial.locate_package_file("x", "example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf")
    except sa.ConfigError:
        pytest.skip("example-robot-data is not installed")
    assert os.path.isfile(path)
    with pytest.raises(sa.ConfigError, match=r"package 'example-robot-data' has no file 'robots/nothing.urdf'"):
        spatial.locate_package_file("x", "example-robot-data", "robots/nothing.urdf")


@pytest.mark.parametrize("name", ["umetani1990-spatial", "ets7", "ur5-smallsat", "arm3dof-100kg"])
def test_example_robot_files_load(name):
    robot = sa.load_robot(os.path.join(CONFIGS, f"{name}.yaml"))
    assert robot.name == name
    assert robot.n_joints == {"umetani1990-spatial": 2, "ets7": 6, "ur5-smallsat": 6, "arm3dof-100kg": 3}[name]


def test_ets7_needs_the_opt_in_for_its_published_inertias(tmp_path):
    import yaml

    with open(os.path.join(CONFIGS, "ets7.yaml"), encoding="utf-8") as handle:
        config = yaml.safe_load(handle)
    config["arm"]["inertia_as_written"] = False
    with pytest.raises(
        sa.ConfigError, match=r"ets7.urdf: link 'link2': inertial inertia: violates the triangle inequality"
    ):
        spatial.load_spatial_robot(config, base_dir=CONFIGS)


def test_construction_validates_the_pytree():
    robot = sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))
    with pytest.raises(sa.ConfigError, match=r"joints\[1\] 'shoulder': link_mass must not be negative"):
        robot.replace(link_mass=np.array([5.0, -1.0, 10.0]))
    with pytest.raises(sa.ConfigError, match=r"joints\[2\] 'elbow': joint_axis must not be zero"):
        robot.replace(joint_axis=np.array([[0, 0, 1.0], [0, 1, 0], [0, 0, 0]]))
    with pytest.raises(sa.ConfigError, match=r"base.mass: must be positive"):
        robot.replace(base_mass=np.float64(0.0))


def test_cli_validate_checks_spatial_files(tmp_path, capsys):
    from spacearm.cli import main

    assert main(["validate", os.path.join(CONFIGS, "ur5-smallsat.yaml")]) == 0
    assert "valid robot (ur5-smallsat, 6 links" in capsys.readouterr().out
    bad = _urdf(mass=-1.0)
    assert main(["validate", _file(tmp_path, urdf_text=bad)]) == 2
    err = capsys.readouterr().err
    assert "arm.urdf: link 'l1': inertial mass: must not be negative" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


def test_batched_validation_is_vectorized_and_names_the_design():
    robot = sa.load_robot(os.path.join(CONFIGS, "arm3dof-100kg.yaml"))
    fields = spatial.robot._LEAF_FIELDS
    batch = {f: np.stack([np.asarray(getattr(robot, f))] * 50) for f in fields}
    spatial.SpatialRobot(**batch, joint_kinds=robot.joint_kinds)  # valid: the one vectorized pass
    batch["link_inertia"] = batch["link_inertia"].copy()
    batch["link_inertia"][17, 2] = -np.eye(3)
    with pytest.raises(
        sa.ConfigError, match=r"design \(17,\): joints\[2\]: link_inertia: must be positive semidefinite"
    ):
        spatial.SpatialRobot(**batch, joint_kinds=robot.joint_kinds)
