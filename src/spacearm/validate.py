"""Deprecated path (one release): use ``spacearm validate`` (:mod:`spacearm.cli.validate`) and
:func:`spacearm._core.schema.read_yaml`."""

import importlib

from ._core.schema import read_yaml as read_yaml


def __getattr__(name):
    # validate_file lives in the command line, the top layer; loaded on first use so that
    # this library-level path never imports spacearm.cli.
    if name == "validate_file":
        return importlib.import_module("spacearm.cli.validate").validate_file
    raise AttributeError(f"module 'spacearm.validate' has no attribute {name!r}")
