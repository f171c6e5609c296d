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
    if expect_bytes is None and not data and _builtin_sha256 is not None:
        return _Stream()  # a stream of unknown length: decided by what it is fed
    n = (memoryview(data).nbytes if data else 0) if expect_bytes is None else int(expect_bytes)
    if _builtin_sha256 is not None and n <= BUILTIN_MAX_BYTES and _spent[0] + n <= BUILTIN_BUDGET_BYTES:
        _spent[0] += n
        return _builtin_sha256(data)
    import hashlib

    return hashlib.sha256(data)


class _Stream:
    """A hash object for a stream of unknown length: Python's own SHA-256 while the stream stays
    within :data:`BUILTIN_MAX_BYTES` and the budget (the bytes fed are kept until then, at most
    that many), else :mod:`hashlib`'s, fed what came so far, for the rest."""

    __slots__ = ("_h", "_kept", "_openssl", "_counted")

    def __init__(self) -> None:
        self._h = _builtin_sha256()
        self._kept = bytearray()
        self._openssl = False
        self._counted = False

    def update(self, data) -> None:
        if not self._openssl:
            b = memoryview(data).cast("B")
            if len(self._kept) + b.nbytes <= min(BUILTIN_MAX_BYTES, BUILTIN_BUDGET_BYTES - _spent[0]):
                self._kept += b
                self._h.update(b)
                return
            import hashlib

            self._h = hashlib.sha256(self._kept)
            self._kept = bytearray()
            self._openssl = True
        self._h.update(data)

    def _settle(self) -> None:
        if not self._openssl and not self._counted:
            _spent[0] += len(self._kept)  # the builtin's bytes count against the budget once
            self._counted = True

    def digest(self) -> bytes:
        self._settle()
        return self._h.digest()

    def hexdigest(self) -> str:
        self._settle()
        return self._h.hexdigest()
