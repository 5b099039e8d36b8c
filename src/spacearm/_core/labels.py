"""Static labels that ride along a pytree without being part of its identity."""

from __future__ import annotations

__all__ = ["Label"]


class Label(str):
    """A design's name, kept in a pytree's static data but ignored by comparisons.

    JAX caches compiled programs by the pytree structure, static data included; a name
    compared as usual would make two identical designs that differ only by name
    compile every kernel twice. All labels compare equal and hash alike, so renaming
    a design reuses the compiled programs.
    """

    __slots__ = ()

    def __eq__(self, other):
        return isinstance(other, Label) or NotImplemented

    def __ne__(self, other):
        return not isinstance(other, Label)

    def __hash__(self):
        return 0x5ACEA2

    def __reduce__(self):
        return (Label, (str(self),))
