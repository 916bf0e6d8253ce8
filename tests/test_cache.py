"""jaxplan.core.cache: bounded content-keyed memoisation and build timing."""

import gc
import weakref

import numpy as np
import pytest

from jaxplan.core.cache import Built, digest, memoize


def test_digest_equal_for_equal_content_distinct_otherwise():
    a = np.zeros((3, 4), bool)
    b = a.copy()
    assert digest(a) == digest(b)
    b[1, 2] = True
    assert digest(a) != digest(b)
    assert digest(a) != digest(a.reshape(4, 3))  # shape counts
    assert digest(np.zeros(4, np.int32)) != digest(np.zeros(4, np.float32))  # dtype counts
    assert digest(a, 1.0) != digest(a, 2.0)
    assert digest(np.asfortranarray(np.arange(6.0).reshape(2, 3))) == digest(np.arange(6.0).reshape(2, 3))


def test_memoize_same_value_for_equal_content_and_distinct_for_different():
    calls = []

    @memoize(maxsize=4, key=lambda arr, scale: (digest(arr), scale))
    def build(arr, scale):
        calls.append(scale)
        return arr.sum() * scale

    a = np.arange(5)
    first = build(a, 2)
    assert build(a.copy(), 2) is first  # equal content, another object: a hit
    assert calls == [2]
    assert build(a + 1, 2) == (a + 1).sum() * 2  # different content: built anew
    assert build(a, 3) == a.sum() * 3  # different setting: built anew
    assert calls == [2, 2, 3]


def test_memoize_is_bounded_least_recently_used():
    calls = []

    @memoize(maxsize=2, key=lambda x: x)
    def build(x):
        calls.append(x)
        return object()

    one = build(1)
    build(2)
    assert build(1) is one  # 1 is now the most recent
    build(3)  # evicts 2
    assert build.cache_info().currsize == 2
    build(2)
    assert calls == [1, 2, 3, 2]
    assert build(1) is not one  # evicted when 2 came back


def test_memoize_does_not_keep_the_arguments():
    class Big:
        pass

    @memoize(maxsize=4, key=lambda obj: "k")
    def build(obj):
        return 1

    big = Big()
    ref = weakref.ref(big)
    assert build(big) == 1
    del big
    gc.collect()
    assert ref() is None


def test_memoize_failed_build_is_not_cached():
    calls = []

    @memoize(maxsize=4, key=lambda x: x)
    def build(x):
        calls.append(x)
        raise ValueError("no")

    for _ in range(2):
        with pytest.raises(ValueError):
            build(1)
    assert calls == [1, 1]


def test_built_reports_its_time_once():
    b = Built.timed(lambda: sum(range(1000)))
    value, seconds = b.take()
    assert value == sum(range(1000)) and seconds > 0
    assert b.take() == (value, 0.0)


def test_map_caches_hit_on_equal_maps():
    import jaxplan as jp
    from jaxplan.grid import cached_collision_map, search_graph

    free = np.ones((6, 7), bool)
    free[2, 3] = False
    g1, g2 = jp.grid_from_array(free), jp.grid_from_array(free.copy())
    assert cached_collision_map(g1) is cached_collision_map(g2)
    assert search_graph(g1).moves is search_graph(g2).moves
    assert search_graph(g2).grid is g2  # the graph names the caller's map
    free[2, 4] = False
    assert cached_collision_map(jp.grid_from_array(free)) is not cached_collision_map(g1)
