"""The YAML/schema layer: one reader, one did-you-mean formatter, the field checks.

Every input file (robot, sweep, design problem) is read by `read_yaml` and
checked with the helpers here, so all errors share one shape: ``<file>: <field>: <reason>``,
raised as `ConfigError` (exit status 2 on the command line).
"""

from __future__ import annotations

import difflib
import math
import os
from collections.abc import Iterable, Mapping
from typing import Any

import yaml

from .errors import ConfigError

__all__ = [
    "read_yaml",
    "describe_yaml_error",
    "did_you_mean",
    "check_keys",
    "is_number",
    "number",
    "integer",
    "choice",
    "number_list",
    "check_memory",
    "robot_file_name",
]


def describe_yaml_error(error: yaml.YAMLError) -> str:
    """One line for a YAML syntax error: ``malformed YAML at line L, column C: what is wrong``."""
    mark = getattr(error, "problem_mark", None)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
    return f"malformed YAML at {where}{problem}"


def read_yaml(path: str | os.PathLike, *, what: str = "YAML file") -> Any:
    """Parse a YAML file; `ConfigError` for a missing, unreadable or malformed file."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as handle:
            return yaml.safe_load(handle)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such {what}") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a directory, not a {what}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a UTF-8 text file") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: {describe_yaml_error(error)}") from None


def did_you_mean(word: str, known: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest known word, or an empty string."""
    hint = difflib.get_close_matches(str(word), sorted(known), n=1)
    return f" (did you mean '{hint[0]}'?)" if hint else ""


def check_keys(where: str, mapping: Mapping, allowed: Iterable[str]) -> None:
    """Refuse the first key of ``mapping`` not in ``allowed``, with a did-you-mean hint.

    ``where`` prefixes the message (``"robot.yaml: base: "``).
    """
    allowed = set(allowed)
    for key in mapping:
        if key not in allowed:
            raise ConfigError(
                f"{where}unknown key '{key}'{did_you_mean(key, allowed)}; allowed keys: {', '.join(sorted(allowed))}"
            )


def is_number(value: Any) -> bool:
    """A real number as YAML gives it (bool is not a number here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def number(where: str, value: Any) -> float:
    """A finite real number, else `ConfigError` naming ``where``."""
    if not is_number(value):
        raise ConfigError(f"{where}: must be a number, got {type(value).__name__} {value!r}")
    if not math.isfinite(value):
        raise ConfigError(f"{where}: must be a finite number, got {value!r}")
    return float(value)


def integer(where: str, value: Any, *, least: int | None = None) -> int:
    """An integer (optionally ``>= least``), else `ConfigError` naming ``where``."""
    if not isinstance(value, int) or isinstance(value, bool) or (least is not None and value < least):
        bound = f" >= {least}" if least is not None else ""
        raise ConfigError(f"{where}: must be an integer{bound}, got {value!r}")
    return value


def choice(where: str, value: Any, options: Iterable[str]) -> str:
    """One of ``options``, else `ConfigError` with a did-you-mean hint."""
    options = tuple(options)
    if value not in options:
        raise ConfigError(f"{where}: must be one of {', '.join(options)}, got {value!r}{did_you_mean(str(value), options)}")
    return value


def number_list(where: str, value: Any, length: int | None = None) -> list[float]:
    """A list of finite numbers (of the given length), else `ConfigError`."""
    if not isinstance(value, (list, tuple)) or (length is not None and len(value) != length):
        size = f" of {length}" if length is not None else ""
        raise ConfigError(f"{where}: must be a list{size} numbers, got {value!r}")
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
    name = config.get("name", "robot")
    if not isinstance(name, str):
        raise ConfigError(f"{source}: name: must be a string, got {name!r}")
    if "base" not in config:
        raise ConfigError(f"{source}: base: missing required key")
    return name
