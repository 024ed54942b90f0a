"""tmpnav's Java class (tmpnav/task/java/EnhspSlot.java): the shipped jar is built from its
source, for Java 17, and a slot records ENHSP's static state and puts it back.

The slot tests share the test process's one JVM (as tests/task/test_enhsp_persistent.py does).
"""

from __future__ import annotations

import hashlib
import random
import struct
import zipfile

import pytest

from tests.task.instances import small_instance
from tmpnav.task import enhsp_jvm
from tmpnav.task.pddl_text import write_task
from tmpnav.task.solve import solve_text

SOURCE = enhsp_jvm.HELPER_JAR.parent / "EnhspSlot.java"
JAVA_17_CLASS_FILE = 61


def _manifest(jar: zipfile.ZipFile) -> dict[str, str]:
    """The jar's main manifest attributes (a line starting with a space continues the one before)."""
    text = jar.read("META-INF/MANIFEST.MF").decode().replace("\r\n", "\n").replace("\n ", "")
    return dict(line.split(": ", 1) for line in text.splitlines() if ": " in line)


def test_the_jar_is_built_from_the_source_beside_it() -> None:
    """After an edit of EnhspSlot.java, `make java` builds the jar again; this says when it was forgotten."""
    with zipfile.ZipFile(enhsp_jvm.HELPER_JAR) as jar:
        built_from = _manifest(jar).get("Source-SHA256")
    assert built_from == hashlib.sha256(SOURCE.read_bytes()).hexdigest(), "run `make java`"


def test_the_class_runs_on_java_17() -> None:
    """tmpnav runs ENHSP on any Java 17+ (tmpnav.java.JAVA_MIN)."""
    with zipfile.ZipFile(enhsp_jvm.HELPER_JAR) as jar:
        head = jar.read("tmpnav/EnhspSlot.class")[:8]
    magic, _minor, major = struct.unpack(">IHH", head)
    assert magic == 0xCAFEBABE and major == JAVA_17_CLASS_FILE


needs_jvm = pytest.mark.skipif(enhsp_jvm.unavailable() is not None, reason=str(enhsp_jvm.unavailable()))


def _sizes(slot: enhsp_jvm._Slot) -> dict[str, int]:
    """The size of every static collection or map the slot records, read by reflection."""
    import jpype

    sizes = {}
    for name in slot.java.recorded():
        owner, field_name = str(name).rsplit(".", 1)
        field = slot.java.load(owner).getDeclaredField(field_name)
        field.setAccessible(True)
        value = field.get(None)
        if isinstance(value, jpype.JClass("java.util.Collection") | jpype.JClass("java.util.Map")):
            sizes[str(name)] = int(value.size())
    return sizes


@needs_jvm
def test_a_slot_records_enhsps_registries_and_puts_them_back_after_a_solve() -> None:
    table, goals = small_instance(random.Random(5), 2, 4, 0.3)
    task = write_task(table, goals, "mixed", min_gain=0.0)
    first = solve_text(task.domain, task.problem, "enhsp-blind", 60.0).actions  # starts the JVM
    slot = enhsp_jvm._JVM.slots.get_nowait()  # the slot that solved, as the solve left it
    fresh = enhsp_jvm._Slot(enhsp_jvm._JVM.jar)
    try:
        assert slot.reusable and fresh.reusable
        assert len(list(fresh.java.recorded())) > 10  # ENHSP's registries (ids, interned names)
        solved, first_values = _sizes(slot), _sizes(fresh)
        assert solved != first_values  # the solve filled some registries
        slot.reset()
        assert _sizes(slot) == first_values
    finally:
        fresh.close()
        enhsp_jvm._JVM.slots.put(slot)
    assert solve_text(task.domain, task.problem, "enhsp-blind", 60.0).actions == first
