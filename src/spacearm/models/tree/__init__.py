"""The tree family: several arms, or one branched URDF, on a free-floating bus (k tips).

- `robot`: the `TreeRobot` pytree (static parents and tip bodies), its validation, and
  `tree_from_chains` (serial arms on their mounts as one tree);
- `primitives`: the pass over the tree and the per-posture primitives (k tips);
- `family`: `TREE`, the family the generic kernels dispatch on;
- `metrics`: tree-only batched kernels (C(q) and the reaction null space over all arms,
  H_m, H*, rotational and dynamic manipulability per tip).
"""

from .family import TREE as TREE, TreeFamily as TreeFamily
from .metrics import (
    arm_inertia as arm_inertia,
    base_twist_map as base_twist_map,
    dynamic_manipulability as dynamic_manipulability,
    mass_matrix as mass_matrix,
    reaction_null_space as reaction_null_space,
    rotational_manipulability as rotational_manipulability,
)
from .robot import (
    TreeLabels as TreeLabels,
    TreeRobot as TreeRobot,
    stack_tree_robots as stack_tree_robots,
    support_mask as support_mask,
    tree_from_chains as tree_from_chains,
)
