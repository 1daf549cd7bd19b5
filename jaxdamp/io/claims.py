"""One writer per output file: an exclusive claim on every output, taken before any compute.

Two jobs given the same ``--out`` (a re-submitted cluster job, two terminals) both pass the
"does the file exist?" check while neither has written it yet; the second one's open then
truncates the file the first is writing, and the first reports success over a corrupt file.
A claim closes that window: :func:`claim` takes an advisory ``flock`` on a lock file beside the
output (``.NAME.lock`` in the same folder) and holds it until :func:`release` (the writer closes
the file) or the end of the process. A second process that claims the same output is refused
at once with :class:`FileBusy`, naming the process that holds it; nothing is opened, let alone
truncated.

* The lock is released by the kernel when its holder dies (``kill -9``, a crash), so a
  leftover lock file never blocks anyone: it is simply claimed again.
* Claims are counted per process (the command claims at its pre-compute check, the file writer
  again when it creates the file), so a process never blocks itself.
* Across hosts (:mod:`jaxdamp.studies.sweep`) only process 0 writes and claims; the others
  only read the checkpoint.
* :func:`changed` tells whether an output was touched since it was claimed, so that a message
  after Ctrl-C names only files that exist and says what they hold.

Example::

    from jaxdamp.io import claims
    claims.claim("run.h5")      # FileBusy if another process writes run.h5
    ...                         # write run.h5
    claims.release("run.h5")
"""

from __future__ import annotations

import os
import sys

from jaxdamp.config import ConfigError


class FileBusy(ConfigError):
    """Another process is writing the output file."""


#: ``abspath -> [fd of the lock file or None, count, stat of the output when first claimed]``
_held: dict[str, list] = {}


def lock_path(path) -> str:
    """The lock file of ``path``: ``.NAME.lock`` beside it."""
    full = os.path.abspath(os.fspath(path))
    folder, name = os.path.split(full)
    return os.path.join(folder, f".{name}.lock")


def _signature(full: str):
    try:
        st = os.stat(full)
    except OSError:
        return None
    return (st.st_ino, st.st_size, st.st_mtime_ns)


def claim(path) -> None:
    """Claim ``path`` for writing by this process (again: counted). Raises :class:`FileBusy`
    naming the holder when another live process has claimed it. Where the folder cannot hold
    a lock file or the file system has no locks, the claim is recorded without a lock."""
    full = os.path.abspath(os.fspath(path))
    if full in _held:
        _held[full][1] += 1
        return
    fd = _lock(full, os.fspath(path))
    _held[full] = [fd, 1, _signature(full)]


def _lock(full: str, shown: str):
    import fcntl

    lock = lock_path(full)
    for _ in range(100):  # the lock file may be removed by its last holder as we open it
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            return None  # a folder that takes no lock file: the pre-compute check said why
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise FileBusy(f"{shown} is being written by another jaxdamp process{holder}; "
                           "wait for it to finish, or choose another --out") from None
        except OSError:  # no flock on this file system (some network mounts)
            os.close(fd)
            return None
        try:
            same = os.fstat(fd).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:
            same = False
        if same:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()} {' '.join(sys.argv)}\n".encode())
            return fd
        os.close(fd)
    return None


def _holder(fd) -> str:
    try:
        text = os.pread(fd, 4096, 0).decode(errors="replace").strip()
    except OSError:
        return ""
    pid, _, command = text.partition(" ")
    if not pid.isdigit():
        return ""
    return f" (pid {pid}" + (f": {command[:120]}" if command else "") + ")"


def release(path) -> None:
    """Undo one :func:`claim` of ``path``; the last one removes the lock file and unlocks."""
    full = os.path.abspath(os.fspath(path))
    entry = _held.get(full)
    if entry is None:
        return
    entry[1] -= 1
    if entry[1] > 0:
        return
    del _held[full]
    fd = entry[0]
    if fd is not None:
        try:
            os.unlink(lock_path(full))  # while still locked: a waiting claimant re-checks
        except OSError:
            pass
        os.close(fd)


def release_all() -> None:
    """Release every claim of this process (the end of a command)."""
    for full in list(_held):
        _held[full][1] = 1
        release(full)


def held(path) -> bool:
    """Whether this process holds a claim on ``path``."""
    return os.path.abspath(os.fspath(path)) in _held


def changed(path) -> bool:
    """Whether ``path`` differs (created, removed, written) from when this process first
    claimed it; ``False`` for a path never claimed."""
    full = os.path.abspath(os.fspath(path))
    entry = _held.get(full)
    return entry is not None and _signature(full) != entry[2]
