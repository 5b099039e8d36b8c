"""The mass a robot file carries, against the URDF's link masses summed by hand.

Merging links into bodies must neither lose nor repeat a kilogram: the budget's total is
the bus plus the URDF subtrees the file takes in (held side branches included, dropped
ones left out), read here straight from the XML.
"""

import os
import xml.etree.ElementTree as ET

import pytest
import yaml

import spacearm as sa
from spacearm.cli import main

from .test_tree_files import erd

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")
ERD = "example-robot-data"
UR5 = "robots/ur_description/urdf/ur5_robot.urdf"
TALOS = "robots/talos_data/robots/talos_reduced.urdf"


def xml_subtree_mass(path: str, link: str, *, drop_movable_except: set[str] | None = None) -> float:
    """Mass of ``link`` and every link below it; with ``drop_movable_except``, a movable
    joint not in that set ends the walk (its child and all below left out)."""
    root = ET.parse(path).getroot()
    mass = {}
    for element in root.findall("link"):
        value = element.find("inertial/mass")
        mass[element.get("name")] = float(value.get("value")) if value is not None else 0.0
    children: dict[str, list] = {}
    for joint in root.findall("joint"):
        children.setdefault(joint.find("parent").get("link"), []).append(joint)

    def below(name: str) -> float:
        total = mass[name]
        for joint in children.get(name, []):
            movable = joint.get("type") != "fixed"
            if drop_movable_except is not None and movable and joint.get("name") not in drop_movable_except:
                continue
            total += below(joint.find("child").get("link"))
        return total

    return below(link)


def budget_total(robot) -> float:
    lines = sa.mass_budget(robot)
    assert lines[-1].part == "total"
    assert lines[-1].kg == pytest.approx(sum(line.kg for line in lines[:-1]), abs=1e-12)
    return lines[-1].kg


def test_dual_ur5_servicer_is_the_bus_plus_both_urdf_subtrees(capsys):
    robot = sa.load_robot(os.path.join(CONFIGS, "dual-ur5-servicer.yaml"))
    expected = float(robot.base_mass) + 2 * xml_subtree_mass(erd(UR5), "base_link")
    assert abs(budget_total(robot) - expected) < 1e-9
    assert main(["info", os.path.join(CONFIGS, "dual-ur5-servicer.yaml")]) == 0
    printed = capsys.readouterr().out
    assert f"{expected:.6f}" in printed and "root left" in printed and "moving links of right" in printed


def _talos_system(tmp_path, **system):
    config = {
        "name": "talos-upper-body",
        "base": {"mass": 800.0, "com": [0, 0, 0], "inertia": [[300, 0, 0], [0, 300, 0], [0, 0, 300]]},
        "mount": {"xyz": [0.0, 0.0, 1.0], "rpy": [0.0, 0.0, 0.0]},
        "system": {
            "urdf": {"package": ERD, "path": TALOS},
            "base_link": "torso_2_link",
            "tips": ["arm_left_7_link", "arm_right_7_link"],
            "inertia_as_written": True,
            **system,
        },
    }
    path = tmp_path / "talos.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def test_a_system_on_a_real_bus_is_the_bus_plus_its_subtree(tmp_path, capsys):
    """A humanoid's upper body (Talos from torso_2_link, head and grippers held) on an 800 kg bus."""
    urdf = erd(TALOS)
    robot = sa.load_robot(_talos_system(tmp_path, lock_others=True))
    subtree = xml_subtree_mass(urdf, "torso_2_link")
    assert abs(budget_total(robot) - (800.0 + subtree)) < 1e-9
    assert budget_total(robot) == pytest.approx(838.560402, abs=5e-7)
    assert float(robot.base_mass) == 800.0 and robot.n_joints == 14
    assert main(["validate", str(_talos_system(tmp_path, lock_others=True))]) == 0
    assert "838.560402" in capsys.readouterr().out


def test_drop_others_leaves_the_side_branches_out(tmp_path):
    urdf = erd(TALOS)
    held = sa.load_robot(_talos_system(tmp_path, lock_others=True))
    dropped = sa.load_robot(_talos_system(tmp_path, drop_others=True))
    kept = set(dropped.joint_names)
    expected = 800.0 + xml_subtree_mass(urdf, "torso_2_link", drop_movable_except=kept)
    assert abs(budget_total(dropped) - expected) < 1e-9
    assert budget_total(dropped) < budget_total(held) - 1.0  # the head and the fingers are gone
    assert dropped.joint_names == held.joint_names


def test_just_the_arm_of_a_humanoid(tmp_path):
    """drop_others on an arm: file: the torso's own links, then the arm alone."""
    urdf = erd(TALOS)
    config = {
        "name": "talos-left-arm",
        "base": {"mass": 800.0, "com": [0, 0, 0], "inertia": [[300, 0, 0], [0, 300, 0], [0, 0, 300]]},
        "mount": {"xyz": [0.0, 0.0, 1.0], "rpy": [0.0, 0.0, 0.0]},
        "arm": {
            "urdf": {"package": ERD, "path": TALOS},
            "root_link": "torso_2_link",
            "tip": "arm_left_7_link",
            "drop_others": True,
            "inertia_as_written": True,
        },
    }
    path = tmp_path / "arm.yaml"
    path.write_text(yaml.safe_dump(config))
    robot = sa.load_robot(path)
    expected = 800.0 + xml_subtree_mass(urdf, "torso_2_link", drop_movable_except=set(robot.joint_names))
    assert abs(budget_total(robot) - expected) < 1e-9
    assert robot.n_joints == 7


def test_a_mount_without_a_bus_and_both_side_branch_rules_are_refused(tmp_path, capsys):
    path = _talos_system(tmp_path, lock_others=True)
    config = yaml.safe_load(path.read_text())
    del config["base"]
    path.write_text(yaml.safe_dump(config))
    assert main(["validate", str(path)]) == 2
    assert "mount: places system.base_link on a bus" in capsys.readouterr().err
    assert main(["validate", str(_talos_system(tmp_path, lock_others=True, drop_others=True))]) == 2
    assert "lock_others or system.drop_others, not both" in capsys.readouterr().err


def test_two_arms_cut_from_one_humanoid_are_flagged(tmp_path, capsys):
    """Before: two Talos arms as an arms: file came to 877.1 kg (the physical 838.6 kg) with no warning."""
    erd(TALOS)
    arm = {"urdf": {"package": ERD, "path": TALOS}, "root_link": "torso_2_link", "lock_others": True}
    config = {
        "name": "talos-two-arms",
        "base": {"mass": 800.0, "com": [0, 0, 0], "inertia": [[300, 0, 0], [0, 300, 0], [0, 0, 300]]},
        "arms": [
            {"name": "left", "tip": "arm_left_7_link", "inertia_as_written": True, **arm},
            {"name": "right", "tip": "arm_right_7_link", "inertia_as_written": True, **arm},
        ],
    }
    path = tmp_path / "arms.yaml"
    path.write_text(yaml.safe_dump(config))
    assert main(["info", str(path)]) == 0
    printed = capsys.readouterr().out
    assert "877.120804" in printed and "carried by more than one arm" in printed and "arm_left_1_link" in printed
    assert main(["info", os.path.join(CONFIGS, "dual-ur5-servicer.yaml")]) == 0
    assert "more than one arm" not in capsys.readouterr().out  # two whole UR5s are two parts
