"""Interactive 3-D views as self-contained offline HTML files (the optional ``view`` extra).

- `model`: the kinematic model as JSON for the browser (`fk.js` evaluates it);
- `page`: one page with plotly.js, the forward kinematics and the data inlined;
- `arm`: a robot on its bus with a slider per joint (``spacearm view``);
- `replay`: a recorded maneuver replayed (``spacearm reach --html``);
- `front`: a Pareto front with the design variables on hover (``spacearm optimize``);
- `shells`: a sweep's workspace shells, design by design (``spacearm sweep``).

Why Plotly: it inlines plotly.js and takes a page script that re-poses the arm
(``Plotly.restyle``), with hover, zoom and turning built in. meshcat's and viser's static
pages are smaller but replay what their local server recorded, so no slider could re-pose
the arm without Python. See docs/guide/views.md.
"""

from .arm import write_arm_view as write_arm_view
from .front import front_view as front_view, write_front_view as write_front_view
from .page import (
    VIEW_EXTRA_MESSAGE as VIEW_EXTRA_MESSAGE,
    MissingViewExtra as MissingViewExtra,
    view_extra_available as view_extra_available,
)
from .replay import replay_from_npz as replay_from_npz, write_replay_view as write_replay_view
from .shells import shells_view as shells_view, write_shells_view as write_shells_view
