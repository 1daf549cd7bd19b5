"""Ctrl-C, handled in one place: asked for at any moment, acted on where nothing is half done.

A ``KeyboardInterrupt`` raised wherever the signal happens to land is unsafe in this program:
inside JAX's import or a garbage-collector callback it is printed and swallowed (the run goes
on); inside XLA's compiler, a numba compilation or an HDF5 write it can leave a half-written
file or crash the interpreter at exit. So the command line installs :func:`install` on its first
line, and from then on a Ctrl-C only *asks*:

* the first Ctrl-C sets a flag and says so; the program stops at its next safe point —
  :func:`check`, called between chunks of every run, sweep and settle (the driver) and between
  the points of the other loops — by raising ``KeyboardInterrupt`` there, where the caller
  marks its file ``interrupted`` and the command names what was kept;
* a second Ctrl-C stops the process at once (exit status 130), as ``kill`` would: the output
  file keeps its last checkpoint, as after any kill.

Outside the command line (a script, a notebook) nothing is installed and Ctrl-C raises as
usual, except while a chunk is computed or written (:class:`held`), where it is deferred to the
end of that chunk.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

#: How many times Ctrl-C was pressed since :func:`install` (or inside :class:`held`).
_asked = 0
_installed = False

FIRST = ("jaxdamp: Ctrl-C: stopping at the next safe point (the end of the current chunk); "
         "press Ctrl-C again to stop at once")
FORCED = ("jaxdamp: stopped at once by a second Ctrl-C; an output file keeps its last "
          "checkpoint (as after a kill)")


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def install() -> None:
    """Make Ctrl-C a request (see the module docstring) for the rest of the process. A no-op
    outside the main thread and where SIGINT is ignored (``nohup``, a background job without
    job control). Installing again keeps a Ctrl-C already asked for (the script installs
    before its imports, :func:`jaxdamp.cli.main` again on its first line)."""
    global _installed, _asked
    if not _main_thread() or signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        return
    if _installed and signal.getsignal(signal.SIGINT) is _on_sigint:
        return
    _asked = 0
    signal.signal(signal.SIGINT, _on_sigint)
    _installed = True


def uninstall() -> None:
    """Back to Python's default Ctrl-C (the end of a command run in-process, e.g. in tests)."""
    global _installed, _asked
    if _installed and _main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
    _installed = False
    _asked = 0


def _on_sigint(signum, frame) -> None:
    global _asked
    _asked += 1
    if _asked == 1:
        _say(FIRST)
        return
    _say(FORCED)
    os._exit(130)


def _say(text: str) -> None:
    try:
        sys.stderr.write("\n" + text + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def asked() -> bool:
    """Whether Ctrl-C was pressed and not yet acted on."""
    return _asked > 0


def check() -> None:
    """A safe point: raise ``KeyboardInterrupt`` if Ctrl-C was asked for."""
    if _asked > 0:
        raise KeyboardInterrupt


class held:
    """``with held():`` — Ctrl-C waits until the block is done, then raises
    ``KeyboardInterrupt`` (a chunk computed or written is never cut in half). Under
    :func:`install` this is just a safe point after the block; otherwise it installs a
    flag-setting handler for the block's duration (main thread, SIGINT not ignored)."""

    def __enter__(self):
        self._old = None
        if (not _installed and _main_thread()
                and signal.getsignal(signal.SIGINT) is not signal.SIG_IGN):
            self._old = signal.signal(signal.SIGINT, self._note)
        return self

    @staticmethod
    def _note(signum, frame):
        global _asked
        _asked += 1

    def __exit__(self, kind, value, tb):
        global _asked
        if self._old is not None:
            signal.signal(signal.SIGINT, self._old)
            if _asked and kind is None:
                _asked = 0
                raise KeyboardInterrupt
            _asked = 0
            return False
        if kind is None:
            check()
        return False
