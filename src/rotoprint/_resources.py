"""What this machine has: available memory, for refusing work that cannot fit."""

from __future__ import annotations

import os

from .constants import MAX_RASTER_MEMORY_FRACTION
from .errors import RasterTooLargeError


def available_memory_bytes() -> int:
    """Memory available to new allocations: /proc/meminfo's MemAvailable (else free physical
    memory), and no more than this process's address-space limit (``ulimit -v``) leaves."""
    free = _system_available_bytes()
    room = _address_space_room_bytes()
    return free if room is None else max(0, min(free, room))


def _address_space_room_bytes() -> int | None:
    """``RLIMIT_AS`` minus the address space already mapped; None without a limit."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft == resource.RLIM_INFINITY or soft < 0:
            return None
        with open("/proc/self/statm", encoding="ascii") as fh:
            mapped = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        return soft - mapped
    except (ImportError, OSError, ValueError):  # pragma: no cover - non-Linux
        return None


def _system_available_bytes() -> int:
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 8 << 30


def format_bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024 or unit == "TiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.1f} TiB"  # pragma: no cover


def check_raster_fits(width: int, height: int, bytes_per_pixel: int, *, what: str = "raster") -> None:
    """Raise :class:`RasterTooLargeError` before allocating a raster that cannot fit.

    ``bytes_per_pixel`` counts every working array the caller keeps per pixel.
    """
    need = int(width) * int(height) * int(bytes_per_pixel)
    limit = available_memory_bytes() * MAX_RASTER_MEMORY_FRACTION
    if need > limit:
        raise RasterTooLargeError(
            f"{what} of {width} x {height} px would need {format_bytes(need)}, "
            f"more than the {format_bytes(limit)} this machine can spare"
        )


def release_free_memory() -> None:
    """Hand freed heap memory back to the operating system (glibc ``malloc_trim``), after
    the large temporaries of mesh loading; a no-op where that call does not exist."""
    import ctypes

    try:  # libc.so.6 first: find_library runs ldconfig / gcc in subprocesses (~20 ms)
        libc = ctypes.CDLL("libc.so.6")
    except OSError:  # pragma: no cover - not glibc
        import ctypes.util  # (imports subprocess: only here)

        try:
            libc = ctypes.CDLL(ctypes.util.find_library("c"))
        except (OSError, TypeError):
            return
    try:
        libc.malloc_trim(0)
    except AttributeError:  # pragma: no cover - not glibc
        pass
