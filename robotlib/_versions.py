"""robotlib's version, and the check a lab makes against it.

Versions are ``MAJOR.MINOR.PATCH`` (CHANGELOG.md). A lab notebook is released
for a ``MAJOR.MINOR`` and names it in its set-up cell
(``robotlib.notebook.setup(requires="0.1")``): an older minor, or another
major, may lack or change what the lab uses; patch releases never do.

A leaf: imports nothing of robotlib.
"""

from __future__ import annotations

__all__ = ["__version__", "lab_version", "version_mismatch"]

__version__ = "0.1.0"
"""This release (read by the build too: ``pyproject.toml``'s dynamic version)."""


def lab_version(version: str = __version__) -> str:
    """Return the ``MAJOR.MINOR`` a lab released with ``version`` names."""
    return ".".join(str(n) for n in _major_minor(version))


def _major_minor(text: str) -> tuple[int, int]:
    parts = text.split(".")
    if len(parts) < 2 or not all(p.isdigit() for p in parts[:2]):
        raise ValueError(f"not a MAJOR.MINOR version: {text!r}")
    return int(parts[0]), int(parts[1])


def version_mismatch(requires: str, installed: str | None = None) -> str | None:
    """Say why a lab released for robotlib ``requires`` may not run here.

    Parameters
    ----------
    requires : str
        ``"MAJOR.MINOR"`` the lab was released for.
    installed : str, optional
        The installed version (default: robotlib's own).

    Returns
    -------
    str or None
        A message for the student, or None when the versions fit.

    Raises
    ------
    ValueError
        If either version is not ``MAJOR.MINOR[.PATCH...]``.
    """
    installed = __version__ if installed is None else installed
    need, have = _major_minor(requires), _major_minor(installed)
    if have[0] == need[0] and have[1] >= need[1]:
        return None
    return (
        f"This lab was released for robotlib {requires}, and robotlib {installed} "
        "is installed: parts of the lab may not run. Install the version your "
        "course uses (`pip install --upgrade` the wheel or clone you were given), "
        "then restart the kernel."
    )
