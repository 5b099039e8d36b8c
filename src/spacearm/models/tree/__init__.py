"""The tree family: several arms, or one branched URDF, on a free-floating bus (k tips).

- `robot`: the `TreeRobot` pytree (static parents and tip bodies), its validation, and
  `tree_from_chains` (serial arms on their mounts as one tree);
- `primitives`: the pass over the tree and the per-posture primitives (k tips);
- `family`: `TREE`, the family the generic kernels dispatch on.

The kernels over H* and the rotational rows of J* serve every robot: `spacearm.inertia`.
"""

from .family import TREE as TREE, TreeFamily as TreeFamily
from .robot import (
    TreeLabels as TreeLabels,
    TreeRobot as TreeRobot,
    stack_tree_robots as stack_tree_robots,
    support_mask as support_mask,
    tree_from_chains as tree_from_chains,
)
