"""The GIL is released while the library computes: another Python thread runs meanwhile, and a
tree is queried from several Python threads at once with the answers of one thread."""

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import nbhd

# a call that releases the GIL lets the probe's thread run about once a millisecond, hundreds of
# times in a 0.1 s call; one that holds it lets it run at most at the call's edges, when a busy
# machine delays the caller by more than the probe's 20 ms margin: the line between is this count
RELEASED = 5


def runs_meanwhile(work):
    """Timestamps at which a second Python thread ran during `work()`, a call into the library:
    with the GIL held by the call, that thread could not run at all until it returned."""
    stamps = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.05)
    start = time.perf_counter()
    work()
    end = time.perf_counter()
    stop.set()
    t.join()
    inside = [s for s in stamps if start + 0.02 < s < end - 0.02]
    return end - start, len(inside)


def long_enough(make_work, n):
    """`runs_meanwhile` of `make_work(n)()`, `n` doubled until the call lasts over 0.1 s: a faster
    library or machine must not leave too short a call to tell whether the GIL was released."""
    while True:
        secs, ticks = runs_meanwhile(make_work(n))
        if secs > 0.1 or n >= 4_000_000:
            return secs, ticks
        n *= 2


def test_gil_is_released_during_tables_and_smoothing(rng):
    def table(n):
        tree = nbhd.KdTree(rng.random((n, 3)))
        return lambda: tree.neighborhoods(k=30, threads=1)

    secs, ticks = long_enough(table, 300_000)
    assert secs > 0.1 and ticks > RELEASED, (secs, ticks)

    def build(n):
        pts = rng.random((n, 3))
        return lambda: nbhd.KdTree(pts, threads=1, median="presorted")

    secs, ticks = long_enough(build, 300_000)
    assert secs > 0.1 and ticks > RELEASED, (secs, ticks)

    def smoothing(n):
        sph = rng.normal(size=(n, 3))
        sph /= np.linalg.norm(sph, axis=1, keepdims=True)
        return lambda: nbhd.smooth(sph, threads=1, steps=5)

    secs, ticks = long_enough(smoothing, 60_000)
    assert secs > 0.1 and ticks > RELEASED, (secs, ticks)


def test_one_tree_queried_from_many_python_threads(rng):
    pts = rng.random((20_000, 3))
    tree = nbhd.KdTree(pts)
    qs = [rng.random((2000, 3)) for _ in range(8)]
    alone = [tree.knn(q, 9, threads=1) for q in qs]
    with ThreadPoolExecutor(4) as ex:
        together = list(ex.map(lambda q: tree.knn(q, 9), qs))
    for (a, b), (c, d) in zip(alone, together):
        assert a.tobytes() == c.tobytes() and b.tobytes() == d.tobytes()


def test_the_probe_sees_a_call_that_holds_the_gil():
    # control: a C call that never releases the GIL (the regex engine backtracking) lets the
    # other thread run hardly at all, so the probe above can fail
    import re

    # lengthen the backtracking (each 'a' about 1.6 times the work) until the call is long
    # enough for the probe's window, however fast the machine
    n = 24
    while True:
        secs, ticks = runs_meanwhile(lambda: re.match("(a|aa)*c", "a" * n))
        if secs > 0.1 or n > 40:
            break
        n += 2
    assert secs > 0.1 and ticks <= RELEASED, (n, secs, ticks)
