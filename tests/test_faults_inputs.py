"""Fault injection: hundreds of generated malformed input files, each refused the same way.

Robot files (planar and spatial), sweep files, design-problem files and URDFs are
mutated field by field (wrong types, NaN, inf, huge numbers, numeric strings YAML reads
as text) and as whole files (empty, binary, deep nesting, alias bombs, duplicate keys,
cycles, orphan links, unknown links). Every case runs in this process through
``spacearm.cli.main`` and must end with exit status 2 and one line on stderr naming the
file and the field, write nothing, and take well under a few seconds and 500 MB.
"""

import copy
import resource
import time
from pathlib import Path

import pytest
import yaml

from spacearm.cli import main

ROOT = Path(__file__).resolve().parents[1]
PLANAR = yaml.safe_load((ROOT / "configs" / "umetani1990.yaml").read_text())
PROBLEM = yaml.safe_load((ROOT / "sweeps" / "pareto-attachment.yaml").read_text())

BAD_NUMBERS = {
    "string": "far",
    "numeric string": "1.0e12",
    "nan": float("nan"),
    "inf": float("inf"),
    "-inf": float("-inf"),
    "huge": 1e300,
    "bool": True,
    "list": [1.0, 2.0],
    "mapping": {"value": 1.0},
}

URDF = """<robot name="t">
  <link name="base"><inertial><mass value="1.0"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l1"><inertial><origin xyz="0.1 0 0"/><mass value="{mass}"/><inertia ixx="{ixx}" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><mass value="1.0"/><inertia ixx="0.05" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"/>
  {links}
  <joint name="j1" type="revolute"><origin xyz="0 0 0.1"/><parent link="base"/><child link="l1"/><axis xyz="{axis}"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="{j2_type}"><origin xyz="{xyz}"/><parent link="{j2_parent}"/><child link="l2"/><axis xyz="0 1 0"/></joint>
  <joint name="tool_joint" type="fixed"><origin xyz="0.4 0 0"/><parent link="l2"/><child link="tool"/></joint>
  {joints}
</robot>"""


def urdf(**changes):
    fields = dict(
        mass="2.0", ixx="0.1", axis="0 0 1", xyz="0.5 0 0", j2_type="continuous", j2_parent="l1", links="", joints=""
    )
    fields.update(changes)
    return URDF.format(**fields)


SPATIAL = {
    "name": "faulty",
    "base": {"mass": 500.0, "com": [0.0, 0.0, 0.0], "inertia": [[80, 0, 0], [0, 90, 0], [0, 0, 100]]},
    "mount": {"xyz": [0.5, 0.0, 0.4], "rpy": [0.0, 0.0, 0.0]},
    "arm": {"urdf": "arm.urdf", "root_link": "base", "tip": "tool"},
}


def sweep_config():
    return {
        "name": "faulty",
        "robot": str(ROOT / "configs" / "umetani1990.yaml"),
        "axes": {"b0": {"field": "base.attach", "values": [0.0, 1.0]}},
        "metrics": ["S_M"],
        "chunk_size": 4,
    }


def put(config, path, value):
    """Set a dotted path (``links[0].mass``) in a nested mapping."""
    node = config
    parts = path.replace("]", "").replace("[", ".").split(".")
    for part in parts[:-1]:
        node = node[int(part)] if isinstance(node, list) else node[part]
    last = parts[-1]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value
    return config


# Every case: (kind, file text, field the message must name, URDF text or None, command).
CASES: dict[str, tuple[str, str, str, str | None]] = {}


def add(name, text, field, urdf_text=None, command="validate"):
    assert name not in CASES, name
    CASES[name] = (text, field, urdf_text, command)


def dump(config):
    return yaml.safe_dump(config, sort_keys=False)


# Field by field ---------------------------------------------------------------------------

for field in [
    "base.mass",
    "base.inertia",
    "base.attach",
    "links[0].mass",
    "links[0].inertia",
    "links[0].a",
    "links[1].b",
]:
    for label, value in BAD_NUMBERS.items():
        add(f"planar {field} {label}", dump(put(copy.deepcopy(PLANAR), field, value)), field)

for field, values in {
    "base.mass": BAD_NUMBERS,
    "base.com": {
        "short": [0, 0],
        "nan": [float("nan"), 0, 0],
        "huge": [1e300, 0, 0],
        "string": "origin",
        "numeric string": ["1.0e12", 0, 0],
        "bool": [True, 0, 0],
    },
    "base.inertia": {
        "flat": [80, 90, 100],
        "nan": [[float("nan"), 0, 0], [0, 90, 0], [0, 0, 100]],
        "huge": [[1e308, 0, 0], [0, 90, 0], [0, 0, 100]],
        "ragged": [[80, 0], [0, 90, 0], [0, 0, 100]],
        "not symmetric": [[80, 5, 0], [0, 90, 0], [0, 0, 100]],
        "triangle": [[1, 0, 0], [0, 1, 0], [0, 0, 5]],
        "string": "heavy",
    },
    "mount.xyz": {
        "huge": [1e300, 0, 0],
        "inf": [float("inf"), 0, 0],
        "long": [0, 0, 0, 0],
        "string": "top",
        "nested": [[0], [0], [0]],
    },
    "mount.rpy": {"nan": [float("nan"), 0, 0], "huge": [0, 1e200, 0], "mapping": {"r": 0}},
    "arm.root_link": {"unknown": "bse", "number": 3, "list": ["base"]},
    "arm.tip": {"unknown": "toool", "number": 7, "null": None},
    "arm.lock_joints": {
        "unknown joint": {"j9": 0.0},
        "nan": {"j2": float("nan")},
        "list": ["j2"],
        "fixed joint": {"tool_joint": 0.0},
        "string value": {"j2": "zero"},
    },
    "arm.inertia_as_written": {"string": "yes", "number": 1},
    "arm.urdf": {
        "missing file": "nowhere.urdf",
        "number": 5,
        "bad package": {"package": "no-such-pkg-xyz", "path": "a"},
    },
}.items():
    for label, value in values.items():
        expected = {"mount.xyz": "mount.xyz", "mount.rpy": "mount.rpy"}.get(field, field)
        add(f"spatial {field} {label}", dump(put(copy.deepcopy(SPATIAL), field, value)), expected, urdf())

for field, values in {
    "axes.b0.values": {
        "empty": [],
        "string": "many",
        "nan": [float("nan")],
        "huge": [1e300],
        "inf": [float("inf")],
        "numeric string": ["1.0e12"],
        "bool": [True],
        "nested": [[1.0]],
    },
    "axes.b0.field": {"unknown": "base.atach", "number": 3},
    "chunk_size": {"zero": 0, "huge": 2**40, "float": 4.5, "string": "big"},
    "metrics": {
        "unknown": ["wbra"],
        "string": 7,
        "bad option": [{"name": "wbar", "order": 10**9}],
        "huge panels": [{"name": "wbar", "phi1_panels": 10**6}],
        "huge directions": [{"name": "straight_path_area", "n_directions": 10**9}],
        "float order": [{"name": "wbar", "order": 1e9}],
    },
    "combine": {"unknown": "zipped"},
    "name": {"spaces": "a b", "number": 5},
    "robot": {"missing": "nowhere.yaml", "number": 5},
}.items():
    for label, value in values.items():
        expected = {"axes.b0.values": "axes.b0", "axes.b0.field": "axes.b0"}.get(field, field)
        add(f"sweep {field} {label}", dump(put(sweep_config(), field, value)), expected, command="sweep")

for field, values in {
    "fixed.base_mass": {"string": "heavy", "nan": float("nan"), "huge": 1e300},
    "fixed.links": {"float": 2.5, "huge": 10**6},
    "variables.b0": {"reversed": [3.0, 0.0], "string": [0.0, "3"], "nan": [0.0, float("nan")]},
    "objectives": {"unknown": ["wbar", "S_GG"], "string": "wbar"},
    "wbar.order": {"huge": 10**9, "zero": 0, "float": 4.0},
    "search.directions": {"huge": 10**8, "zero": 0},
    "search.starts": {"huge": 10**9},
    "search.steps": {"string": "many"},
    "search.learning_rate": {"negative": -1.0, "inf": float("inf")},
    "baselines.nsga2.population": {"huge": 10**9},
    "baselines.grid.points": {"huge": [10**6, 10**6]},
}.items():
    for label, value in values.items():
        add(f"problem {field} {label}", dump(put(copy.deepcopy(PROBLEM), field, value)), field)

# Whole files -------------------------------------------------------------------------------

BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, "
    f"*{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}, *{chr(97 + i)}]\n"
    for i in range(8)
)
WHOLE = {
    "empty": ("", "neither a robot file"),
    "only a comment": ("# nothing\n", "neither a robot file"),
    "a list": ("- 1\n- 2\n", "neither a robot file"),
    "a scalar": ("42\n", "neither a robot file"),
    "binary": ("\x00\x01\x02\xff", ""),
    "tabs": ("name:\tx\n\tbase: 1\n", "malformed YAML"),
    "unclosed": ("base: {mass: 1\n", "malformed YAML"),
    "deep nesting": ("a: " + "[" * 5000 + "]" * 5000 + "\n", "nest"),
    "deep mappings": ("".join("  " * i + f"k{i}:\n" for i in range(200)) + "  " * 200 + "v: 1\n", "nest"),
    "alias bomb": (BOMB, "expands to more than"),
    "recursive alias": ("a: &a [1, *a]\n", "alias"),
    "python tag": ("base: !!python/object/apply:os.system ['true']\n", "malformed YAML"),
}
for name, (text, field) in WHOLE.items():
    add(f"file {name}", text, field)

for kind, config in (("planar", PLANAR), ("spatial", SPATIAL), ("sweep", sweep_config()), ("problem", PROBLEM)):
    text = dump(config)
    first = text.splitlines()[0]
    add(f"{kind} duplicate top key", text + first + "\n", "duplicate key")
    add(f"{kind} alias bomb in description", BOMB + text, "expands to more than", urdf() if kind == "spatial" else None)
    add(
        f"{kind} deep value",
        text.replace(first, first.split(":")[0] + ": " + "[" * 300 + "]" * 300, 1),
        "nest",
        urdf() if kind == "spatial" else None,
    )

add(
    "planar duplicate link key",
    "name: dup\nbase: {mass: 1000.0, inertia: 635.3, attach: 1.4}\nlinks:\n"
    "  - {mass: 100.0, inertia: 33.3, a: 1.0, b: 1.0, mass: 50.0}\n  - {mass: 100.0, inertia: 33.3, a: 1.0, b: 1.0}\n",
    "duplicate key 'mass'",
)
add(
    "sweep duplicate axis",
    "name: faulty\nrobot: " + str(ROOT / "configs" / "umetani1990.yaml") + "\naxes:\n"
    "  b0: {field: base.attach, values: [0.0]}\n  b0: {field: base.mass, values: [1.0]}\nmetrics: [S_M]\n",
    "duplicate key 'b0'",
    command="sweep",
)
add(
    "sweep alias bomb in values",
    "name: faulty\nrobot: "
    + str(ROOT / "configs" / "umetani1990.yaml")
    + "\n"
    + BOMB
    + "axes:\n  b0: {field: base.attach, values: *i}\nmetrics: [S_M]\n",
    "expands to more than",
    command="sweep",
)

# URDFs (through the spatial robot file that names them) -------------------------------------

URDFS = {
    "cycle through root_link": (
        urdf(joints='<joint name="back" type="fixed"><parent link="l2"/><child link="base"/></joint>'),
        "form a cycle",
    ),
    "fixed cycle": (
        urdf(
            links='<link name="a"/><link name="b"/>',
            joints='<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
            '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>',
        ),
        "'ab', 'ba'",
    ),
    "orphan tree": (
        urdf(
            links='<link name="ghost"><inertial><mass value="1000"/><inertia ixx="1" iyy="1" izz="1" ixy="0" '
            'ixz="0" iyz="0"/></inertial></link><link name="ghost2"/>',
            joints='<joint name="g" type="fixed"><parent link="ghost"/><child link="ghost2"/></joint>',
        ),
        "'ghost', 'ghost2' are not connected",
    ),
    "lone orphan": (urdf(links='<link name="stray"/>'), "'stray'"),
    "unknown parent": (urdf(j2_parent="l7"), "joint 'j2': parent link 'l7' is not defined"),
    "huge inertia": (urdf(ixx="1e308"), "link 'l1'"),
    "nan inertia": (urdf(ixx="nan"), "link 'l1'"),
    "inf mass": (urdf(mass="inf"), "link 'l1'"),
    "negative mass": (urdf(mass="-2"), "link 'l1'"),
    "overflowing axis": (urdf(axis="1e200 1e200 0"), "joint 'j1': axis xyz"),
    "zero axis": (urdf(axis="0 0 0"), "joint 'j1': axis xyz"),
    "short xyz": (urdf(xyz="0.5 0"), "joint 'j2': origin xyz"),
    "word xyz": (urdf(xyz="a b c"), "joint 'j2': origin xyz"),
    "floating joint": (urdf(j2_type="floating"), "joint 'j2': type 'floating'"),
    "unknown type": (urdf(j2_type="hinge"), "joint 'j2': unknown type"),
    "duplicate link": (urdf(links='<link name="l1"/>'), "link 'l1' is defined twice"),
    "duplicate joint": (
        urdf(
            links='<link name="x"/>',
            joints='<joint name="j1" type="fixed"><parent link="l2"/><child link="x"/></joint>',
        ),
        "joint 'j1' is defined twice",
    ),
    "two parents": (
        urdf(joints='<joint name="j3" type="fixed"><parent link="base"/><child link="l2"/></joint>'),
        "already has parent joint",
    ),
    "malformed": (urdf()[:-30], "malformed XML"),
    "not a robot": ("<world/>", "root element must be <robot>"),
    "empty": ("", "malformed XML"),
    "binary": ("\x00\x01garbage", "malformed XML"),
    "entity bomb": (
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
        + "".join(f'<!ENTITY {chr(98 + i)} "{("&" + chr(97 + i) + ";") * 10}">' for i in range(8))
        + ']><robot name="&i;"/>',
        "arm.urdf",
    ),
    "external entity": (
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>'
        '<robot name="&x;"><link name="base"/></robot>',
        "arm.urdf",
    ),
    "long chain": (
        "<robot name='c'>"
        + "".join(f"<link name='l{i}'/>" for i in range(2001))
        + "".join(
            f"<joint name='j{i}' type='revolute'><parent link='l{i}'/><child link='l{i + 1}'/><axis xyz='0 0 1'/>"
            "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint>"
            for i in range(2000)
        )
        + "</robot>",
        "at most 64",
    ),
}
for name, (text, field) in URDFS.items():
    config = copy.deepcopy(SPATIAL)
    if name == "long chain":
        config["arm"].update(root_link="l0", tip="l2000")
    add(f"urdf {name}", dump(config), field, text)


def test_there_are_at_least_150_cases():
    assert len(CASES) >= 150, len(CASES)


@pytest.mark.parametrize("name", sorted(CASES))
def test_malformed_input_is_one_line_exit_2_nothing_written(name, tmp_path, capsys):
    text, field, urdf_text, command = CASES[name]
    path = tmp_path / "input.yaml"
    path.write_bytes(text.encode("utf-8", "surrogatepass") if "\x00" not in text else text.encode("latin-1"))
    if urdf_text is not None:
        (tmp_path / "arm.urdf").write_text(urdf_text)
    out = tmp_path / "out"
    argv = ["validate", str(path)] if command == "validate" else ["sweep", str(path), "--out", str(out), "--quiet"]
    before = sorted(p.name for p in tmp_path.iterdir())
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert str(path) in err, err  # names the file
    assert field in err, err  # and the field
    if urdf_text is not None and name.startswith("urdf"):
        assert "arm.urdf" in err
    assert len(err) < 1000, len(err)  # quotes at most a few hundred characters of any value
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    assert elapsed < 10, elapsed
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - peak < 500 * 1024  # KiB: under 500 MB more


def test_oversized_file_is_refused_before_parsing(tmp_path, capsys):
    path = tmp_path / "big.yaml"
    path.write_text("description: '" + "x" * (9 * 2**20) + "'\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "at most 8,388,608 are read" in err and err.count("\n") == 1


def test_interrupt_during_start_up_is_one_line(monkeypatch, capsys):
    """Ctrl-C while the command line starts (building the parser, importing a command)."""
    import spacearm.cli as cli

    def interrupted():
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    assert cli.main(["validate", "x.yaml"]) == 130
    err = capsys.readouterr().err
    assert err == "spacearm: interrupted\n"


def test_unwritable_output_is_one_line(tmp_path, capsys, monkeypatch):
    """An OSError from a command (a read-only or full disk) is one line, exit 1."""
    import spacearm.cli.validate as validate

    def full_disk(args):
        raise OSError(28, "No space left on device", str(tmp_path / "out" / "x.npz"))

    monkeypatch.setattr(validate, "run", full_disk)
    assert main(["validate", "x.yaml"]) == 1
    err = capsys.readouterr().err
    assert err == f"spacearm validate: error: {tmp_path / 'out' / 'x.npz'}: No space left on device\n"
