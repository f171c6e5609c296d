"""Reused image buffers (rotoprint._buffers): a block comes back only when nothing else holds it."""

from __future__ import annotations

import pickle
import threading

import numpy as np

from rotoprint._buffers import ReusedBuffers


def test_a_dropped_block_is_handed_out_again():
    pool = ReusedBuffers(4)
    a = pool.take((3, 5))
    addr = a.ctypes.data
    assert a.shape == (3, 5) and a.dtype == np.uint8 and a.flags.c_contiguous
    del a
    b = pool.take((3, 5))
    assert b.ctypes.data == addr  # the same block
    assert len(pool) == 1


def test_a_block_still_held_in_any_form_is_not_reused():
    pool = ReusedBuffers(8)
    holders = {
        "array": lambda a: a,
        "view": lambda a: a[1:],
        "memoryview": lambda a: memoryview(a),
        "in a list": lambda a: [a],
        "transposed": lambda a: a.T,
    }
    for name, hold in holders.items():
        a = pool.take((4, 6))
        a[:] = 7
        kept = hold(a)
        addr = a.ctypes.data
        del a
        b = pool.take((4, 6))
        assert b.ctypes.data != addr, name
        b[:] = 1  # writing the new block leaves the held one as it was
        assert (np.asarray(kept) == 7).all(), name
        del kept, b


def test_other_shapes_and_dtypes_get_new_blocks():
    pool = ReusedBuffers(4)
    a = pool.take((2, 8))
    held = [a]  # a block of this size stays held so that a new one cannot land at its address
    addr = a.ctypes.data
    del a
    b = pool.take((8, 2))
    c = pool.take((2, 8), np.int16)
    assert (b.shape, b.dtype, c.shape, c.dtype) == ((8, 2), np.uint8, (2, 8), np.int16)
    assert addr not in (b.ctypes.data, c.ctypes.data)
    del held
    d = pool.take((2, 8))
    assert (d.shape, d.dtype, d.ctypes.data) == ((2, 8), np.uint8, addr)  # the dropped one, of its own shape


def test_keep_bounds_what_is_held_and_zero_keeps_nothing():
    pool = ReusedBuffers(2)
    blocks = [pool.take((10,)) for _ in range(5)]
    assert len(pool) == 2
    newest = {b.ctypes.data for b in blocks[-2:]}
    del blocks
    assert {pool.take((10,)).ctypes.data, pool.take((10,)).ctypes.data} <= newest  # the two held, reused
    none = ReusedBuffers(0)
    a = none.take((10,))
    assert len(none) == 0 and a.shape == (10,)  # none are held: a new block each time


def test_pickles_empty_and_threads_never_share_a_block():
    pool = ReusedBuffers(3)
    kept = pool.take((5,))
    clone = pickle.loads(pickle.dumps(pool))
    assert clone.keep == 3 and len(clone) == 0 and len(pool) == 1
    del kept
    seen, bad, lock = [], [], threading.Lock()

    def work(seed):
        for _ in range(200):
            a = pool.take((64,))
            a[:] = seed
            with lock:
                seen.append((seed, a.ctypes.data))
            if not (a == seed).all():  # another thread wrote into it meanwhile
                bad.append(seed)

    ts = [threading.Thread(target=work, args=(s,)) for s in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert len(seen) == 800 and not bad


def test_a_weakly_held_block_stays_the_callers():
    import weakref

    pool = ReusedBuffers(4)
    a = pool.take((8,))
    a[:] = 5
    w = weakref.ref(a)
    addr = a.ctypes.data
    del a  # only the pool and the weak reference hold it
    b = pool.take((8,))
    b[:] = 9
    assert b.ctypes.data != addr and w() is not None and (w() == 5).all()


def _reads_locals(frame, event, arg):
    frame.f_locals  # (a debugger's or tracer's view: on 3.11 it copies the locals onto the frame)
    return _reads_locals


def test_a_tracer_reading_locals_never_makes_a_held_block_look_free():
    # helper-56's case: the baseline measured while a tracer read the frame's locals was one too high,
    # and a print held once by the caller was written over; now the counts are read on the list's items
    import importlib
    import sys

    import rotoprint._buffers as mod

    old = sys.gettrace()
    sys.settrace(_reads_locals)
    try:
        fresh = importlib.reload(mod)  # the baseline measured under the tracer
        traced = fresh.ReusedBuffers(4)
        a = traced.take((16,))
        kept = a
        del a
        b = traced.take((16,))  # taken under the tracer too
    finally:
        sys.settrace(old)
    try:
        assert b.ctypes.data != kept.ctypes.data
        pool = fresh.ReusedBuffers(4)
        x = pool.take((32,))
        x[:] = 3
        held = x
        addr = x.ctypes.data
        del x
        y = pool.take((32,))
        y[:] = 4
        assert y.ctypes.data != addr and (held == 3).all()
        del held
        assert pool.take((32,)).ctypes.data == addr  # dropped: reused
    finally:
        importlib.reload(mod)
