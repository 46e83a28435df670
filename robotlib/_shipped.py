"""Where the files shipped beside the package are: worlds, released labs, syllabus.

A checkout (or an editable install, or the grading sandbox, which binds the
package beside its ``worlds/``) reads them from the folders beside the
package (``worlds/``, ``labs/``, ``course/``); a wheel or sdist install puts
them under ``share/robotlib/`` of its prefix (``pyproject.toml``'s
``data-files``), which is a virtual environment's ``sys.prefix``, or the user
base for ``pip install --user``. The repository's folders stay the only copy:
the build reads them, nothing copies them by hand.

A leaf: imports nothing of robotlib.
"""

from __future__ import annotations

import site
import sys
from pathlib import Path

__all__ = ["CHECKOUT", "shipped_dir"]

_ROOT = Path(__file__).resolve().parents[1]
CHECKOUT = _ROOT if (_ROOT / "pyproject.toml").is_file() else None
"""The repository this package runs from (a checkout or an editable install), or
None for an installed package."""


def _prefixes() -> list[Path]:
    prefixes = [Path(sys.prefix)]
    user_base = getattr(site, "USER_BASE", None)
    if user_base:
        prefixes.append(Path(user_base))
    return prefixes


def shipped_dir(name: str) -> Path:
    """Return the folder of shipped files ``name`` (``"worlds"``, ``"labs"``, ...).

    Parameters
    ----------
    name : str
        A top-level folder of the repository that the package ships.

    Returns
    -------
    pathlib.Path
        The checkout's ``name/`` when this package runs from a checkout, else
        the first ``PREFIX/share/robotlib/name`` that exists (``sys.prefix``'s
        when none does).
    """
    if CHECKOUT is not None or (_ROOT / name).is_dir():
        # a checkout: also inside the grading sandbox, which binds the
        # package and its worlds beside it but not pyproject.toml
        return _ROOT / name
    candidates = [prefix / "share" / "robotlib" / name for prefix in _prefixes()]
    return next((path for path in candidates if path.is_dir()), candidates[0])
