"""tmpnav's Java classes (tmpnav/task/java/*.java, ENHSP's server and its slots): the shipped
jar is built from their sources, for Java 17. What they do is tested through the server, in
tests/task/test_enhsp_persistent.py (a slot reused in another order plans the same, a
search stopped at its limit, the server's end with the run)."""

from __future__ import annotations

import hashlib
import struct
import zipfile

from tmpnav.task import enhsp_jvm

SOURCES = sorted(enhsp_jvm.HELPER_JAR.parent.glob("*.java"))
JAVA_17_CLASS_FILE = 61


def _manifest(jar: zipfile.ZipFile) -> dict[str, str]:
    """The jar's main manifest attributes (a line starting with a space continues the one before)."""
    text = jar.read("META-INF/MANIFEST.MF").decode().replace("\r\n", "\n").replace("\n ", "")
    return dict(line.split(": ", 1) for line in text.splitlines() if ": " in line)


def test_the_jar_is_built_from_the_source_beside_it() -> None:
    """After an edit of EnhspSlot.java, `make java` builds the jar again; this says when it was forgotten."""
    with zipfile.ZipFile(enhsp_jvm.HELPER_JAR) as jar:
        built_from = _manifest(jar).get("Source-SHA256")
    assert built_from == hashlib.sha256(b"".join(p.read_bytes() for p in SOURCES)).hexdigest(), "run `make java`"


def test_the_class_runs_on_java_17() -> None:
    """tmpnav runs ENHSP on any Java 17+ (tmpnav.java.JAVA_MIN)."""
    with zipfile.ZipFile(enhsp_jvm.HELPER_JAR) as jar:
        for name in ("tmpnav/EnhspServer.class", "tmpnav/EnhspSlot.class"):
            magic, _minor, major = struct.unpack(">IHH", jar.read(name)[:8])
            assert magic == 0xCAFEBABE and major == JAVA_17_CLASS_FILE
