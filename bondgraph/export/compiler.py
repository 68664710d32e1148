"""The system C compiler: finding it and building a shared library from C99 sources."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

from ..support.errors import UsageError

#: flags of every build: C99, optimised, a position-independent shared library that exports
#: only the fmi2 functions (so two FMUs in one process never call into each other)
FLAGS = ("-std=c99", "-O2", "-fPIC", "-shared", "-fvisibility=hidden")


def find_compiler(cc: str | None = None) -> str:
    """The path of the C compiler ``cc`` (default ``$CC``, else ``cc``).

    Parameters
    ----------
    cc : str, optional
        The compiler's name or path.

    Returns
    -------
    str
        Its full path.

    Raises
    ------
    UsageError
        No such compiler on the PATH.
    """
    cc = cc or os.environ.get("CC") or "cc"
    found = shutil.which(cc)
    if found is None:
        raise UsageError(f"no C compiler '{cc}' found: install one (e.g. apt-get install gcc) or set CC")
    return found


def build_shared(cc: str, directory: Path, sources: list[str], output: Path) -> str | None:
    """Compile ``sources`` (file names in ``directory``) into the shared library ``output``;
    returns None on success, else the compiler's first error line.

    Parameters
    ----------
    cc : str
        The compiler's path.
    directory : pathlib.Path
        The working directory holding the sources.
    sources : list of str
        C file names in ``directory``.
    output : pathlib.Path
        The shared library to write.

    Returns
    -------
    str or None
        None on success, else the compiler's first error line.
    """
    cmd = [cc, *FLAGS, "-o", str(output), *sources, "-lm"]
    proc = subprocess.run(cmd, cwd=directory, capture_output=True, text=True)
    if proc.returncode == 0:
        return None
    lines = proc.stderr.splitlines()
    return next((ln.strip() for ln in lines if "error" in ln), lines[0].strip() if lines else "unknown failure")
