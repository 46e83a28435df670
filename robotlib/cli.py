"""The ``robotlib`` command line: one entry point, subcommands loaded lazily.

Each subcommand lives in its own module, which provides
``add_arguments(parser)`` and ``run(args) -> int``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = {
    "sim-server": (
        "robotlib.pioneer.server",
        "serve the simulator over the Pioneer protocol",
    ),
    "reproduce": (
        "robotlib.experiments.reproduce",
        "run the paper's MCL experiment over many seeds",
    ),
    "bench": ("robotlib.experiments.benchmarks", "measure a topic against its peers"),
    "faulty-link": (
        "robotlib.pioneer.faults",
        "a proxy to sim-server that delays and drops packets",
    ),
    "course": (
        "robotlib.course.folder",
        "write the released labs and the syllabus into a folder of your own",
    ),
    "release": ("robotlib.course.release", "write labs/ from solutions/"),
    "grade": ("robotlib.course.command", "grade a folder of submissions in a sandbox"),
    "validate": (
        "robotlib.course.validate",
        "check a lab notebook before handing it in",
    ),
    "warmup": ("robotlib.notebook", "compile the numba kernels the labs use, once"),
}
"""Subcommand name to (module, one-line help)."""


def _version() -> str:
    from robotlib._versions import __version__

    return __version__


def main(argv: list[str] | None = None) -> int:
    """Run the ``robotlib`` command line; return the exit status."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(
        prog="robotlib", description="robotlib: mobile-robotics courseware tools."
    )
    parser.add_argument("--version", action="version", version=f"robotlib {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_, help_) in COMMANDS.items():
        sub.add_parser(name, help=help_, add_help=False)
    if not argv or argv[0] not in COMMANDS:
        args = parser.parse_args(argv)
        parser.print_help()
        return 2
    module = importlib.import_module(COMMANDS[argv[0]][0])
    cmd_parser = argparse.ArgumentParser(prog=f"robotlib {argv[0]}")
    module.add_arguments(cmd_parser)
    args = cmd_parser.parse_args(argv[1:])
    return int(module.run(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
