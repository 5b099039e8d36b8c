"""The one error type a user sees for bad input."""

from __future__ import annotations

__all__ = ["ConfigError", "RunError", "Stalled"]


class ConfigError(ValueError):
    """A robot, sweep or design-problem description is invalid.

    The message names the file, the field (or the link or joint) and the reason; the
    command line prints it on one line and exits with status 2.
    """


class RunError(RuntimeError):
    """A run that started could not finish correctly (a result came out NaN, a peer
    process died or disagrees). The command line prints the message on one line and
    exits with status 1.
    """


class Stalled(RunError):
    """A computation stopped making progress (no CPU used for a long wait): the threads
    that ran it are stuck, so the command line prints one line and ends the process at
    once (exit status 1) instead of waiting for them at interpreter exit.
    """
