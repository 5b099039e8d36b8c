"""Validation of YAML inputs by kind: a robot file, a sweep file or a design problem."""

from __future__ import annotations

import os

import yaml

from .robot import ConfigError, describe_yaml_error, robot_from_mapping


def read_yaml(path: str | os.PathLike) -> object:
    """Parse a YAML file; ConfigError for a missing, unreadable or malformed file."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as handle:
            return yaml.safe_load(handle)
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a directory, not a YAML file") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a UTF-8 text file") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: {describe_yaml_error(error)}") from None


def validate_file(path: str | os.PathLike) -> tuple[str, str]:
    """Validate a robot, sweep or design-problem file; return (kind, one-line summary) or raise ConfigError."""
    path = os.fspath(path)
    config = read_yaml(path)
    if isinstance(config, dict) and ("links" in config or "base" in config):
        robot = robot_from_mapping(config, source=path)
        return "robot", f"{robot.name}, {robot.n_links} links, L = {float(robot.reach):g} m"
    if isinstance(config, dict) and ("axes" in config or "robot" in config):
        from .sweep import load_sweep  # the sweep module validates its own schema

        spec = load_sweep(path)
        return "sweep", spec.summary()
    if isinstance(config, dict) and ("variables" in config or "objectives" in config):
        from .design import load_problem  # the design module validates its own schema

        problem = load_problem(path)
        names = ", ".join(getattr(problem, "variable_names", ()) or [])
        return "design problem", f"{config.get('name', path)}" + (f": variables {names}" if names else "")
    raise ConfigError(
        f"{path}: neither a robot file (needs 'base' and 'links'), a sweep file (needs 'robot' and 'axes') "
        "nor a design problem (needs 'variables' and 'objectives')"
    )
