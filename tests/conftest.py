"""Tests run in float64 (the package itself never flips the global flag on import)."""

import jax
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

import spacearm as sa  # noqa: E402


@pytest.fixture
def table1():
    """The Table 1 robot of Umetani & Yoshida 1990."""
    return sa.umetani1990()


def random_robot(rng: np.random.Generator, n: int, name: str = "random") -> sa.PlanarRobot:
    """A random valid design with n links (masses 10-1000 kg, lengths 0.3-3 m)."""
    a = rng.uniform(0.1, 1.5, n)
    b = rng.uniform(0.1, 1.5, n)
    m = rng.uniform(10.0, 200.0, n)
    inertia = m * (a + b) ** 2 / 12.0 * rng.uniform(0.5, 2.0, n)
    m0 = rng.uniform(100.0, 2000.0)
    return sa.PlanarRobot(
        base_mass=np.float64(m0),
        base_inertia=np.float64(m0 * rng.uniform(0.2, 2.0)),
        base_attach=np.float64(rng.uniform(0.0, 2.5)),
        link_mass=m,
        link_inertia=inertia,
        link_a=a,
        link_b=b,
        name=name,
    )
