"""The real ``tmpnav serve`` in a process of its own, on a free port and a cache directory of
the test's: started, waited for, stopped (or killed) by the test."""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ADDRESS = re.compile(r"at (http://\S+/) ")


class Server:
    """``tmpnav serve SCENARIO --port 0`` with ``args``; ``url`` once it listens."""

    def __init__(self, scenario: str, cache: Path, *args: str, logs: Path | None = None):
        self.cache = cache
        self.log = (logs or cache) / f"serve-{time.monotonic_ns()}.log"
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        self.process = subprocess.Popen(
            [sys.executable, "-m", "tmpnav", "serve", scenario, "--port", "0", "--cache-dir", str(cache), *args],
            cwd=ROOT,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=self.log.open("w"),
            start_new_session=True,
        )
        self.url = self._address(120.0)

    def _address(self, seconds: float) -> str:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if (m := ADDRESS.search(self.log.read_text())) is not None:
                url = m.group(1)
                try:
                    urllib.request.urlopen(url + "health", timeout=5).close()
                    return url.rstrip("/")
                except OSError as err:
                    if "401" in str(err):  # with --token: up, and guarded
                        return url.rstrip("/")
            if self.process.poll() is not None:
                raise RuntimeError(f"tmpnav serve ended ({self.process.returncode}): {self.log.read_text()}")
            time.sleep(0.2)
        self.stop()
        raise RuntimeError(f"tmpnav serve did not start in {seconds} s: {self.log.read_text()}")

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self) -> None:
        """SIGTERM, then SIGKILL after 20 s; the process group too (ENHSP, the oracle's workers)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.kill()
        self._group(signal.SIGKILL)

    def kill(self) -> None:
        """SIGKILL, as a crash: no cleanup of its own."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait(20)

    def _group(self, sig: signal.Signals) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, sig)
