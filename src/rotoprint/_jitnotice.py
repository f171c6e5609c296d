"""A progress line for numba compiles: the first run after an install compiles the jit kernels
it touches (seconds to a minute; cached on disk next to the sources afterwards), and the user
is told so instead of waiting in silence.

:func:`install` is called by the CLI before a command runs. It does not import numba (the DLP
path never needs it): an import hook waits for numba to be imported by a kernel module and
then registers a listener for numba's ``numba:compile`` event, which fires only when a kernel
is compiled (a kernel loaded from the disk cache fires nothing). On a terminal the line is a
rich status that updates in place; elsewhere (make, CI logs) one line per kernel.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
import time

_STATE = {"installed": False, "done": 0, "depth": 0, "t0": 0.0, "spent": 0.0, "status": None}


def _say(console, text: str) -> None:
    st = _STATE
    if console.is_terminal:
        if st["status"] is None:
            st["status"] = console.status(text, spinner="dots")
            st["status"].start()
        else:
            st["status"].update(text)
    else:
        console.print(text, soft_wrap=True)


def _listener(console):
    from numba.core import event

    class _Notice(event.Listener):
        def on_start(self, ev):
            st = _STATE
            st["depth"] += 1
            if st["depth"] == 1:
                st["t0"] = time.perf_counter()
                disp = ev.data.get("dispatcher") if isinstance(ev.data, dict) else None
                name = getattr(getattr(disp, "py_func", None), "__qualname__", "kernel")
                mod = getattr(getattr(disp, "py_func", None), "__module__", "")
                _say(console, f"compiling jit kernel {st['done'] + 1}: {mod}.{name} "
                              "(first run after install; cached on disk afterwards)")

        def on_end(self, ev):
            st = _STATE
            st["depth"] -= 1
            if st["depth"] == 0:
                st["done"] += 1
                st["spent"] += time.perf_counter() - st["t0"]

    return _Notice()


def _register(console) -> None:
    from numba.core import event

    event.register("numba:compile", _listener(console))


class _AfterImport(importlib.abc.MetaPathFinder):
    """Finds nothing itself; wraps numba's loader so that the listener is registered as soon
    as numba has been imported."""

    def __init__(self, console) -> None:
        self.console = console

    def find_spec(self, fullname, path, target=None):
        if fullname != "numba":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return spec
        loader, console = spec.loader, self.console
        exec_module = loader.exec_module

        def exec_and_register(module):
            exec_module(module)
            try:
                _register(console)
            except Exception:  # noqa: BLE001 - a notice must never break a run
                pass

        loader.exec_module = exec_and_register
        return spec


def install(console) -> None:
    """Show numba compiles on ``console`` (a rich Console) from now on; idempotent.

    Only on a terminal, or with ``ROTOPRINT_COMPILE_NOTICE=1`` (the install's warm-up sets
    it): output captured by scripts and tests stays as it was.
    """
    import os

    if _STATE["installed"]:
        return
    if not (console.is_terminal or os.environ.get("ROTOPRINT_COMPILE_NOTICE") == "1"):
        return
    _STATE["installed"] = True
    if "numba" in sys.modules:
        _register(console)
    else:
        sys.meta_path.insert(0, _AfterImport(console))


def finish(console) -> None:
    """Close the status line and say how long compiling took (when anything was compiled)."""
    st = _STATE
    if st["status"] is not None:
        st["status"].stop()
        st["status"] = None
    if st["done"]:
        console.print(f"compiled {st['done']} jit kernel(s) in {st['spent']:.0f} s; "
                      "later runs load them from the cache", soft_wrap=True)
        st["done"], st["spent"] = 0, 0.0
