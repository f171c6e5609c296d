"""rotoprint._hashing.sha256 gives hashlib's digests whichever implementation it picks."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys

import pytest

from rotoprint import _hashing


@pytest.mark.parametrize("n", [0, 1, 63, 64, 1000, _hashing.BUILTIN_MAX_BYTES, _hashing.BUILTIN_MAX_BYTES + 1, 3 << 20])
def test_same_digest_as_hashlib(n):
    data = os.urandom(n)
    assert _hashing.sha256(data).hexdigest() == hashlib.sha256(data).hexdigest()
    h = _hashing.sha256(expect_bytes=n)  # fed in pieces
    for k in range(0, n, 4097):
        h.update(memoryview(data)[k : k + 4097])
    assert h.hexdigest() == hashlib.sha256(data).hexdigest()
    assert h.digest() == hashlib.sha256(data).digest()


def test_small_inputs_skip_openssl_until_the_budget_is_spent():
    code = (
        "import sys\n"
        "from rotoprint import _hashing as H\n"
        "for _ in range(10):\n"
        "    H.sha256(b'x' * 10_000).hexdigest()\n"
        "print('_hashlib' in sys.modules)\n"
        "H.sha256(b'x' * (H.BUILTIN_MAX_BYTES + 1))\n"
        "print('_hashlib' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    if _hashing._builtin_sha256 is None:
        pytest.skip("this Python has no built-in SHA-256 module: OpenSSL's is used throughout")
    assert out == ["False", "True"]


@pytest.mark.parametrize("n", [0, 5, _hashing.BUILTIN_MAX_BYTES, _hashing.BUILTIN_MAX_BYTES + 1, 3 << 20])
def test_a_stream_of_unknown_length_gives_hashlibs_digest_and_leaves_the_builtin_when_large(n, monkeypatch):
    monkeypatch.setattr(_hashing, "_spent", [0])
    data = os.urandom(n)
    h = _hashing.sha256()  # no data, no expect_bytes: a stream (a written file, a marker's canon)
    for k in range(0, n, 65537):
        h.update(data[k : k + 65537])
    assert h.hexdigest() == hashlib.sha256(data).hexdigest()
    assert h.digest() == hashlib.sha256(data).digest()
    if _hashing._builtin_sha256 is not None:
        # a large stream goes to OpenSSL's (about 5 x faster), a small one stays with the builtin
        assert h._openssl == (n > _hashing.BUILTIN_MAX_BYTES)
