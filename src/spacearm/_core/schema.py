"""The YAML/schema layer: one reader, one did-you-mean formatter, the field checks.

Every input file (robot, sweep, design problem) is read by `read_yaml` and
checked with the helpers here, so all errors share one shape: ``<file>: <field>: <reason>``,
raised as `ConfigError` (exit status 2 on the command line).
"""

from __future__ import annotations

import difflib
import math
import os
import re
import reprlib
import stat
from collections.abc import Iterable, Mapping
from typing import Any

import yaml

from .errors import ConfigError

__all__ = [
    "MAX_MAGNITUDE",
    "MAX_OBJECTIVES",
    "MAX_QUOTE",
    "MAX_YAML_BYTES",
    "MAX_YAML_DEPTH",
    "MAX_YAML_NODES",
    "SIZE_LIMITS",
    "check_keys",
    "check_memory",
    "check_name",
    "choice",
    "describe_yaml_error",
    "did_you_mean",
    "integer",
    "is_number",
    "number",
    "number_list",
    "quote",
    "read_regular_file",
    "read_yaml",
    "robot_file_name",
]


# Bounds on what a file may hold: documented in docs/guide/guarantees.md, checked before
# anything of that size is built.
MAX_YAML_BYTES = 8 * 2**20  # a YAML file's size
MAX_YAML_NODES = 1_000_000  # values after alias expansion (an "alias bomb" expands exponentially)
MAX_YAML_DEPTH = 64  # nesting of mappings and lists
MAX_MAGNITUDE = 1e15  # |x| of a number read from a file: far from float64 (and float32) overflow
MAX_QUOTE = 200  # characters of a value quoted in a message
MAX_OBJECTIVES = 6  # a design problem's objectives: the hypervolume's cost is exponential in them
MAX_NAME_CHARS = 128  # a robot's, sweep's or problem's name, which becomes a file or folder name

_QUOTER = reprlib.Repr()
_QUOTER.maxlevel, _QUOTER.maxdict, _QUOTER.maxlist, _QUOTER.maxtuple = 3, 6, 8, 8
_QUOTER.maxstring, _QUOTER.maxother, _QUOTER.maxlong = MAX_QUOTE, MAX_QUOTE, 40
# A YAML 1.1 float needs a dot, and a sign in its exponent; PyYAML reads '1e12' or
# '1.0e12' as a string (see `number`).
_LOOKS_NUMERIC = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def quote(value: Any, limit: int = MAX_QUOTE) -> str:
    """``repr(value)`` for a message, at most ``limit`` characters, never expanding a huge or
    shared (aliased) structure in full."""
    text = _QUOTER.repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def describe_yaml_error(error: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: ``malformed YAML at line L, column C: what is wrong``."""
    mark = getattr(error, "problem_mark", None)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    return f"malformed YAML at {where}{problem[:MAX_QUOTE]}"


class _Refused(Exception):
    """A YAML document the reader refuses (the message, without the file name)."""


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses duplicate keys, and documents whose values nest
    deeper than `MAX_YAML_DEPTH` or expand (through aliases) to more than `MAX_YAML_NODES`."""

    def construct_document(self, node):
        _check_size(node)
        return super().construct_document(node)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict[Any, yaml.Node] = {}
            for key_node, _ in node.value:
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = (key_node.tag, key_node.value)
                if key in seen:
                    first = seen[key].start_mark.line + 1
                    raise _Refused(
                        f"line {key_node.start_mark.line + 1}: duplicate key {quote(key_node.value)} "
                        f"(first given on line {first}); each key may appear once"
                    )
                seen[key] = key_node
        return super().construct_mapping(node, deep=deep)


def _check_size(root: yaml.Node) -> None:
    """Count the values of a composed document as construction would expand them (aliases
    are shared nodes), without recursion and without expanding them."""
    sizes: dict[int, tuple[int, int]] = {}  # id(node) -> (values, depth)
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    active: set[int] = set()
    while stack:
        node, done = stack.pop()
        key = id(node)
        if done:
            active.discard(key)
            children = _children(node)
            count = 1 + sum(sizes[id(c)][0] for c in children)
            depth = 1 + max((sizes[id(c)][1] for c in children), default=0)
            if count > MAX_YAML_NODES:
                raise _Refused(
                    f"line {node.start_mark.line + 1}: the document expands to more than "
                    f"{MAX_YAML_NODES:,} values (aliases repeated inside aliases?)"
                )
            if depth > MAX_YAML_DEPTH:
                raise _Refused(f"line {node.start_mark.line + 1}: values nest more than {MAX_YAML_DEPTH} levels deep")
            sizes[key] = (count, depth)
            continue
        if key in sizes:
            continue
        if key in active:
            raise _Refused(f"line {node.start_mark.line + 1}: an alias refers to a value that contains it")
        active.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node) if id(child) not in sizes)


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [item for pair in node.value for item in pair]
    return []


def read_regular_file(path: str | os.PathLike, *, what: str, limit: int) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes; `ConfigError` naming the
    file and the reason otherwise.

    A FIFO, a device or a folder is refused without reading from it (the open never
    blocks), and so is a path that cannot name a file (a NUL byte, a loop of symbolic
    links, a name too long, a path under a file).
    """
    path = os.fspath(path)
    if "\0" in path:
        raise ConfigError(f"{quote(path)}: a file name cannot hold a NUL byte")
    try:
        handle = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such {what}") from None
    except PermissionError:
        raise ConfigError(f"{path}: cannot read the {what} (permission denied)") from None
    except OSError as error:
        raise ConfigError(f"{path}: cannot read the {what} ({error.strerror or error})") from None
    with os.fdopen(handle, "rb") as stream:
        info = os.fstat(handle)
        if stat.S_ISDIR(info.st_mode):
            raise ConfigError(f"{path}: is a directory, not a {what}")
        if not stat.S_ISREG(info.st_mode):
            raise ConfigError(f"{path}: not a regular file (a pipe or a device?); give the {what} itself")
        if info.st_size > limit:
            raise ConfigError(f"{path}: the {what} is {info.st_size:,} bytes; at most {limit:,} are read")
        try:
            data = stream.read(limit + 1)
        except OSError as error:
            raise ConfigError(f"{path}: cannot read the {what} ({error.strerror or error})") from None
    if len(data) > limit:
        raise ConfigError(f"{path}: the {what} is over {limit:,} bytes")
    return data


def read_yaml(path: str | os.PathLike, *, what: str = "YAML file") -> Any:
    """Parse a YAML file; `ConfigError` for a missing, unreadable, malformed or oversized file.

    Refused as well: anything but a regular file (`read_regular_file`), a file over
    `MAX_YAML_BYTES`, a key given twice in one mapping, values nested deeper than
    `MAX_YAML_DEPTH`, and aliases that expand past `MAX_YAML_NODES` values. Only the first
    document is read.
    """
    data = read_regular_file(path, what=what, limit=MAX_YAML_BYTES)
    path = os.fspath(path)
    try:
        text = data.decode("utf-8")
        loader = _StrictLoader(text)
        try:
            return loader.get_single_data()
        finally:
            loader.dispose()
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a UTF-8 text file") from None
    except _Refused as error:
        raise ConfigError(f"{path}: {error}") from None
    except RecursionError:
        raise ConfigError(f"{path}: values nest too deeply (at most {MAX_YAML_DEPTH} levels)") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: {describe_yaml_error(error)}") from None


def check_name(where: str, name: Any) -> str:
    """``name``, checked before it becomes a file or folder name (``results/<name>/``,
    ``<name>.html``): a string of 1 to `MAX_NAME_CHARS` printable characters, with no
    path separator, not ``.`` or ``..``; `ConfigError` naming ``where`` otherwise."""
    if not isinstance(name, str):
        raise ConfigError(f"{where}: must be a string, got {quote(name)}")
    reason = None
    if not name:
        reason = "must not be empty"
    elif len(name) > MAX_NAME_CHARS:
        reason = f"is {len(name)} characters long; at most {MAX_NAME_CHARS}"
    elif not name.isprintable():
        reason = "holds a control character (a NUL byte, a newline, an escape)"
    elif "/" in name or "\\" in name or os.sep in name:
        reason = "holds a path separator; it names a file, not a path"
    elif name in (".", ".."):
        reason = "cannot be '.' or '..'"
    if reason:
        raise ConfigError(f"{where}: {quote(name, 60)} {reason}")
    return name


def did_you_mean(word: str, known: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest known word, or an empty string."""
    word = word[:100] if isinstance(word, str) else quote(word, 100)  # never expand a huge value
    hint = difflib.get_close_matches(word, sorted(known), n=1)
    return f" (did you mean '{hint[0]}'?)" if hint else ""


def check_keys(where: str, mapping: Mapping, allowed: Iterable[str]) -> None:
    """Refuse the first key of ``mapping`` not in ``allowed``, with a did-you-mean hint.

    ``where`` prefixes the message (``"robot.yaml: base: "``).
    """
    allowed = set(allowed)
    for key in mapping:
        if key not in allowed:
            raise ConfigError(
                f"{where}unknown key {quote(str(key), 60)}{did_you_mean(str(key), allowed)}; "
                f"allowed keys: {', '.join(sorted(allowed))}"
            )


def is_number(value: Any) -> bool:
    """A real number as YAML gives it (bool is not a number here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def number(where: str, value: Any) -> float:
    """A finite real number of magnitude at most `MAX_MAGNITUDE`, else `ConfigError` naming ``where``."""
    if not is_number(value):
        if isinstance(value, str) and _LOOKS_NUMERIC.fullmatch(value.strip()):
            raise ConfigError(
                f"{where}: must be a number, got the string {quote(value)} (YAML 1.1 reads a number with an "
                "exponent only with a dot and a signed exponent, e.g. 1.0e+12)"
            )
        raise ConfigError(f"{where}: must be a number, got {type(value).__name__} {quote(value)}")
    if not math.isfinite(value):
        raise ConfigError(f"{where}: must be a finite number, got {quote(value)}")
    if abs(value) > MAX_MAGNITUDE:
        raise ConfigError(f"{where}: must be at most {MAX_MAGNITUDE:g} in magnitude, got {quote(value)}")
    return float(value)


# Upper bounds of every size-like option, by the option's name (the last name in the
# field path given to `integer`): each sizes an array or a loop, and a bound checked when
# the file is read keeps a typo (order: 1e9) from allocating gigabytes before any check.
# Listed in docs/guide/guarantees.md.
SIZE_LIMITS: dict[str, int] = {
    "order": 64,  # Gauss-Legendre points per panel
    "phi1_panels": 4096,
    "phi2_panels": 4096,
    "n_points_joint": 2048,
    "newton_steps": 200,
    "n_directions": 20_000,
    "directions": 4096,  # Pareto search rays
    "starts": 65_536,
    "steps": 100_000,
    "descent_steps": 100_000,
    "chunk": 2**20,
    "chunk_size": 2**20,
    "block": 2**20,
    "randomizations": 1024,
    "min_samples": 2**28,
    "max_samples": 2**28,
    "samples": 2**24,
    "initial_samples": 2**20,
    "keep": 65_536,
    "candidates": 65_536,
    "population": 4096,  # non-dominated sorting compares every pair: (2 x population)^2 x objectives bytes
    "evaluations": 10**8,
    "links": 64,
    "seed": 2**32 - 1,
}


def integer(where: str, value: Any, *, least: int | None = None, most: int | None = None) -> int:
    """An integer in ``least .. most``, else `ConfigError` naming ``where``.

    ``most`` defaults to the `SIZE_LIMITS` entry of the field's name (the last name in
    ``where``), so every size-like option is bounded wherever it is read.
    """
    if most is None:
        names = re.findall(r"[A-Za-z_][A-Za-z0-9_]*", where)
        most = SIZE_LIMITS.get(names[-1]) if names else None
    if not isinstance(value, int) or isinstance(value, bool) or (least is not None and value < least):
        bound = f" >= {least}" if least is not None else ""
        if isinstance(value, float) and value.is_integer() and (least is None or value >= least):
            raise ConfigError(
                f"{where}: must be an integer{bound}, got the float {quote(value)} (write it without a dot or exponent)"
            )
        raise ConfigError(f"{where}: must be an integer{bound}, got {quote(value)}")
    if most is not None and value > most:
        raise ConfigError(
            f"{where}: must be at most {most:,} (a size; larger values would not fit in memory or time), got {value:,}"
        )
    return value


def choice(where: str, value: Any, options: Iterable[str]) -> str:
    """One of ``options``, else `ConfigError` with a did-you-mean hint."""
    options = tuple(options)
    if value not in options:
        hint = did_you_mean(value, options) if isinstance(value, str) else ""
        raise ConfigError(f"{where}: must be one of {', '.join(options)}, got {quote(value)}{hint}")
    return value


def number_list(where: str, value: Any, length: int | None = None) -> list[float]:
    """A list of finite numbers (of the given length), else `ConfigError`."""
    if not isinstance(value, (list, tuple)) or (length is not None and len(value) != length):
        size = f" of {length}" if length is not None else ""
        raise ConfigError(f"{where}: must be a list{size} numbers, got {quote(value)}")
    return [number(f"{where}[{i}]", v) for i, v in enumerate(value)]


def check_memory(where: str, need_bytes: float, what: str, advice: str) -> None:
    """Refuse input whose arrays would not fit in memory (they are built at once), before
    anything that large is allocated: more than half of this machine's RAM is refused.

    Args:
        where: the field, for the message.
        need_bytes: the estimated size.
        what: what needs it (``"1,000,000 designs (a x b)"``).
        advice: how to make it fit.
    """
    try:
        have = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return
    if need_bytes > have / 2:
        raise ConfigError(
            f"{where}: {what} need about {need_bytes / 2**30:,.0f} GiB, "
            f"more than half of this machine's {have / 2**30:.0f} GiB; {advice}"
        )


def robot_file_name(source: str, config: Any, allowed: Iterable[str]) -> str:
    """Check a robot file's top level (a mapping, known keys, a ``base``) and return its name."""
    if not isinstance(config, Mapping):
        raise ConfigError(f"{source}: the robot description must be a mapping, got {type(config).__name__}")
    check_keys(f"{source}: ", config, allowed)
    name = check_name(f"{source}: name", config.get("name", "robot"))
    if "base" not in config:
        raise ConfigError(f"{source}: base: missing required key")
    return name
