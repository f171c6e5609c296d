"""SHA-256 for the journal, the job fingerprint and the ownership markers, without OpenSSL's
start-up on a short job.

``import hashlib`` loads OpenSSL (``_hashlib``), which lists every digest its providers offer
when it starts: about 5 ms, as much as a 10-layer DLP job's journal, fingerprint and marker
hash in all. Python's own SHA-256 (the ``_sha256`` / ``_sha2`` module, no OpenSSL) needs no such
start but hashes at about a fifth of OpenSSL's speed on a CPU with SHA instructions (300 against
1600 MB/s on the project's VM). So small inputs are hashed by Python's own code until a process
has hashed :data:`BUILTIN_BUDGET_BYTES` that way, and anything larger, or anything after that,
by :mod:`hashlib`. Both give the same digests (``tests/test_hashing.py``).
"""

from __future__ import annotations

try:  # Python 3.12+
    from _sha2 import sha256 as _builtin_sha256
except ImportError:  # pragma: no cover - the module's name before 3.12
    try:
        from _sha256 import sha256 as _builtin_sha256
    except ImportError:  # a build without it: OpenSSL's only
        _builtin_sha256 = None

__all__ = ["sha256", "BUILTIN_MAX_BYTES", "BUILTIN_BUDGET_BYTES"]

#: Inputs up to this size may go to Python's own SHA-256 ...
BUILTIN_MAX_BYTES = 256 * 1024
#: ... until a process has hashed this much there (then OpenSSL's start-up is worth paying).
BUILTIN_BUDGET_BYTES = 2 * 1024 * 1024

_spent = [0]


def sha256(data=b"", *, expect_bytes: int | None = None):
    """A SHA-256 hash object (``update``, ``digest``, ``hexdigest``), as
    :func:`hashlib.sha256`, fed ``data`` (any buffer).

    Parameters
    ----------
    data : bytes-like
    expect_bytes : int, optional
        How many bytes the object will be fed in all, ``data`` included (default: ``len(data)``);
        what decides between the two implementations.

    Returns
    -------
    hash object
    """
    n = (memoryview(data).nbytes if data else 0) if expect_bytes is None else int(expect_bytes)
    if _builtin_sha256 is not None and n <= BUILTIN_MAX_BYTES and _spent[0] + n <= BUILTIN_BUDGET_BYTES:
        _spent[0] += n
        return _builtin_sha256(data)
    import hashlib

    return hashlib.sha256(data)
