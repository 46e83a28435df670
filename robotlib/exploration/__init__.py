"""Exploration: frontiers, frontier choice, one robot and a team exploring.

- `classify`, `frontier_cells`, `frontier_regions`, `find_frontiers`: free
  cells next to unknown ones on an occupancy grid, grouped in `Frontier`
  regions with a size and a centroid; `open_frontier` drops those facing
  only a small closed pocket (the inside of a box).
- `known_space`, `frontier_costs`, `departure`, `information_gain`,
  `utility`, `discount`, `choose`: path costs on the known map (unknown
  cells as obstacles, the turn before setting off counted), Burgard et
  al.'s utility and its coordination of a team.
- `ExploreSettings`, `Exploration`, `explore`: the loop (map with the
  robot's own laser or sonar from the true pose or SLAM's, choose, plan with
  A*, follow, avoid, re-plan, go home); `Member`: one robot in it, its
  belief and path (with the checks that keep it clear in `member`).
- `team_starts`, `explore_team`: 2-4 robots in one simulator, one map.
- `reachable_area`, `explored_fraction`, `ExplorationResult`: judged by the
  true world.

Nothing here plots: `robotlib.plotting.exploration` draws what it returns.
"""

from .choice import (
    STRATEGIES,
    choose,
    departure,
    discount,
    frontier_costs,
    information_gain,
    known_space,
    utility,
)
from .explore import Exploration, explore
from .frontiers import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    Frontier,
    classify,
    find_frontiers,
    frontier_cells,
    frontier_regions,
    open_frontier,
)
from .member import DONE, EXPLORE, HOME, Member
from .metrics import ExplorationResult, explored_fraction, reachable_area, time_to
from .settings import POSES, SENSORS, ExploreSettings
from .team import explore_team, team_starts

__all__ = [
    "DONE",
    "EXPLORE",
    "FREE",
    "HOME",
    "OCCUPIED",
    "POSES",
    "SENSORS",
    "STRATEGIES",
    "UNKNOWN",
    "Exploration",
    "ExplorationResult",
    "ExploreSettings",
    "Frontier",
    "Member",
    "choose",
    "classify",
    "departure",
    "discount",
    "explore",
    "explore_team",
    "explored_fraction",
    "find_frontiers",
    "frontier_costs",
    "frontier_cells",
    "frontier_regions",
    "information_gain",
    "known_space",
    "open_frontier",
    "reachable_area",
    "team_starts",
    "time_to",
    "utility",
]
