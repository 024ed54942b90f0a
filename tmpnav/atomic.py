"""Writing files all or nothing: every output and cache file of tmpnav is written here.

A group of files (``plan.json``, ``plan.png`` and the PDDL files of one plan) is written in two
phases. First each file is written in full to a hidden temporary file beside its target (the
same directory, so that the rename is atomic on POSIX), flushed to disk, and given the mode a
new file gets under the umask. Then the temporary files are renamed over their targets.

- If any content fails (a figure that cannot be drawn, a full disk), nothing is renamed and
  the temporary files are removed: the files of an earlier run stay as they were, and a
  directory created for this write is removed again.
- If a rename fails part-way (a target that is a directory, a permission changed), the
  targets already replaced get their earlier content back (kept as hard links until the
  group is done), and the error names the target, never a temporary file.
- A process killed while writing cannot remove its temporary files. They are named
  ``.<name>.tmpnav-<pid>-<random>.tmp``, so the next write into the same directory removes
  those whose process is gone (or that are older than a day).
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path

from tmpnav.lifetime import check_signals, signals_held

#: what a file is written from: its text (UTF-8), its bytes, or a function that writes it
#: to the path it is given (a figure's ``savefig``)
Content = str | bytes | Callable[[Path], None]

_TEMP = re.compile(r"^\..+\.tmpnav-(?P<pid>\d+)-[0-9a-f]+\.(?:tmp|bak)$")
STALE_AFTER = 24 * 3600.0  # s: a temporary file this old is stale whatever its process


def write_files(directory: Path, contents: Mapping[str, Content]) -> list[Path]:
    """Write every ``name -> content`` into ``directory`` (created if missing), all or nothing.

    A name may lead into a sub-folder (``nav2/r1.csv``: the plan and its waypoint files are
    one group). Returns the paths written, in the order of ``contents``. On any error no
    file of this write is left behind, the earlier files are as they were, the folders this
    write created are removed, and the error propagates (an ``OSError`` names the target file).
    """
    directory = Path(directory)
    targets = [_inside(directory, name) for name in contents]
    created: list[Path] = []  # folders this write made, outermost first
    staged: list[tuple[Path, Path]] = []  # (temporary file, target)
    try:
        for folder in dict.fromkeys(t.parent for t in targets):
            created += _make_folder(folder)
            remove_stale(folder)
        for target, content in zip(targets, contents.values(), strict=True):
            with signals_held():  # created and recorded as one step: an interrupt between leaked it
                tmp = _temporary(target, "tmp")
                staged.append((tmp, target))
            try:
                _stage(tmp, content)
            except OSError as err:
                raise _about(err, target) from None
        check_signals()  # an interrupt that the drawing code swallowed: keep the earlier files
        _commit(staged)
    except BaseException:
        _discard(tmp for tmp, _ in staged)
        for folder in reversed(created):
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    return [target for _, target in staged]


def _inside(directory: Path, name: str) -> Path:
    """``directory / name`` for a relative name that stays inside ``directory``."""
    relative = Path(name)
    if relative.is_absolute() or ".." in relative.parts or not relative.parts:
        raise ValueError(f"{name!r} is not a file name inside {directory}")
    return directory / relative


def _make_folder(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; returns those created, outermost first."""
    missing = [p for p in (folder, *folder.parents) if not p.exists()][::-1]
    folder.mkdir(parents=True, exist_ok=True)
    return missing


def write_file(path: Path, content: Content) -> Path:
    """Write one file atomically (see :func:`write_files`)."""
    path = Path(path)
    return write_files(path.parent, {path.name: content})[0]


def remove_stale(directory: Path) -> int:
    """Remove the temporary files that killed writers left in ``directory``; returns how many."""
    removed = 0
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return 0
    now = time.time()
    for entry in entries:
        match = _TEMP.match(entry.name)
        if match is None or not entry.is_file(follow_symlinks=False):
            continue
        try:
            old = now - entry.stat(follow_symlinks=False).st_mtime > STALE_AFTER
        except OSError:
            continue
        if old or not _alive(int(match["pid"])):
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed += 1
    return removed


def public_mode() -> int:
    """The mode a newly created file gets under the current umask (temporary files start 0600)."""
    try:  # Linux reports the umask without changing it (os.umask would, process-wide, for an instant)
        with open("/proc/self/status", encoding="ascii") as fh:
            mask = next(int(line.split()[1], 8) for line in fh if line.startswith("Umask:"))
    except (OSError, StopIteration, ValueError, IndexError):
        mask = os.umask(0)
        os.umask(mask)
    return 0o666 & ~mask


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def _temporary(target: Path, kind: str) -> Path:
    """A new, empty, hidden file beside ``target`` (exclusive creation: never someone else's)."""
    while True:
        path = target.with_name(f".{target.name}.tmpnav-{os.getpid()}-{secrets.token_hex(4)}.{kind}")
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
            return path
        except FileExistsError:
            continue


def _stage(tmp: Path, content: Content) -> None:
    """Write ``content`` to ``tmp``, flush it to disk, give it the umask's mode."""
    if isinstance(content, str | bytes):
        data = content.encode("utf-8") if isinstance(content, str) else content
        with open(tmp, "wb") as fh:
            fh.write(data)
    else:
        content(tmp)
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.chmod(tmp, public_mode())


def _commit(staged: list[tuple[Path, Path]]) -> None:
    """Rename every temporary file over its target; on a failure, put the earlier files back.

    Ctrl-C and SIGTERM are held during the renames (a rename and its record are one step) and
    during a put-back; one that came during the renames is raised when they end, and puts the
    earlier files back too: an interrupted run keeps them."""
    replaced: list[tuple[Path, Path | None]] = []  # (target, its earlier content or None)
    try:
        with signals_held():
            for tmp, target in staged:
                backup = _keep(target)
                replaced.append((target, backup))
                try:
                    os.replace(tmp, target)
                except OSError as err:
                    replaced.pop()
                    _discard([backup] if backup is not None else [])
                    raise _about(err, target) from None
    except BaseException:
        with signals_held():
            for target, backup in reversed(replaced):
                with contextlib.suppress(OSError):
                    if backup is None:
                        target.unlink()
                    else:
                        os.replace(backup, target)
        raise
    finally:
        with signals_held():
            _discard(backup for _, backup in replaced if backup is not None)


def _keep(target: Path) -> Path | None:
    """A second name for the current content of ``target`` (None when there is no such file)."""
    if not target.is_file() or target.is_symlink():
        return None
    backup = _temporary(target, "bak")
    try:
        os.unlink(backup)
        os.link(target, backup)
    except OSError:  # a file system without hard links: a copy does the same
        shutil.copy2(target, backup)
    return backup


def _about(err: OSError, target: Path) -> OSError:
    """The same error, naming the file the user asked for instead of a temporary one."""
    if err.errno is None:
        return err
    return OSError(err.errno, err.strerror, str(target))


def _discard(paths: Iterable[Path]) -> None:
    for path in paths:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(path)
