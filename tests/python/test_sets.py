# simit.Set: field views share the fields' storage (zero copy both ways), their shapes and
# dtypes, edge-set connectivity and its checks.
import gc
import re

import numpy as np
import pytest

import simit

# One field of every component kind and of three shapes, each changed by a run in a way numpy
# can check: a float, an int, a bool, a complex, a vector and a 2x3 matrix.
KINDS_PROGRAM = """
element P
  a : float;
  i : int;
  b : bool;
  c : complex;
  v : vector[3](float);
  M : matrix[2,3](float);
end

extern ps : set{P};

func touch(inout p : P)
  p.a = 2.0 * p.a + 1.0;
  p.i = 3 * p.i - 1;
  p.b = not p.b;
  p.c = p.c * <0.0, 1.0>;
  p.v = p.v + [1.0, 2.0, 3.0]';
  p.M = -p.M;
end

export func step()
  apply touch to ps;
end
"""

# An edge set whose run reads both endpoints, so the connectivity is what the run uses.
EDGES_PROGRAM = """
element Q
  w : float;
end

element E
  s : float;
end

extern qs : set{Q};
extern es : set{E}(qs, qs);

func sum_ends(inout e : E, q : (Q * 2))
  e.s = q(0).w + 10.0 * q(1).w;
end

export func ends()
  apply sum_ends to es;
end
"""

N = 5


def data_ptr(a):
    return a.__array_interface__["data"][0]


def kinds_set():
    s = simit.Set(N)
    s.add_field("a", float)
    s.add_field("i", int)
    s.add_field("b", bool)
    s.add_field("c", complex)
    s.add_field("v", float, shape=(3,))
    s.add_field("M", float, shape=(2, 3))
    return s


def fill(s, rng):
    values = {
        "a": rng.standard_normal(N),
        "i": rng.integers(-1000, 1000, N).astype(np.int32),
        "b": rng.integers(0, 2, N).astype(bool),
        "c": rng.standard_normal(N) + 1j * rng.standard_normal(N),
        "v": rng.standard_normal((N, 3)),
        "M": rng.standard_normal((N, 2, 3)),
    }
    for name, value in values.items():
        s[name][...] = value
    return values


def touched(values):
    """What one run of KINDS_PROGRAM makes of `values`, computed by numpy."""
    return {
        "a": 2.0 * values["a"] + 1.0,
        "i": 3 * values["i"] - 1,
        "b": ~values["b"],
        "c": values["c"] * 1j,
        "v": values["v"] + np.array([1.0, 2.0, 3.0]),
        "M": -values["M"],
    }


def assert_fields(s, expected):
    for name, value in expected.items():
        np.testing.assert_array_equal(s[name], value, err_msg=name)


def compiled(source, name):
    return simit.Program(source=source).compile(name)


@pytest.mark.parametrize(
    "dtype, expected",
    [
        (float, np.float64),
        (int, np.int32),
        (bool, np.bool_),
        (complex, np.complex128),
        (np.float64, np.float64),
        (np.int32, np.int32),
        (np.bool_, np.bool_),
        (np.complex128, np.complex128),
    ],
)
@pytest.mark.parametrize("shape", [(), (3,), (2, 3)])
def test_field_shape_and_dtype(dtype, expected, shape):
    s = simit.Set(N)
    view = s.add_field("f", dtype, shape=shape)
    assert view.shape == (N, *shape)
    assert view.dtype == np.dtype(expected)
    assert view.flags.c_contiguous and view.flags.writeable
    assert not view.any()  # fields start at zero
    assert s["f"].shape == (N, *shape) and s["f"].dtype == np.dtype(expected)
    assert data_ptr(view) == data_ptr(s["f"])


def test_set_size_and_field_names():
    s = kinds_set()
    assert len(s) == N
    assert sorted(s.fields()) == sorted(["a", "i", "b", "c", "v", "M"])
    assert len(simit.Set(0)) == 0


def test_two_reads_share_one_pointer():
    s = kinds_set()
    for name in s.fields():
        assert data_ptr(s[name]) == data_ptr(s[name]), name
    # Different fields are different storage.
    assert len({data_ptr(s[name]) for name in s.fields()}) == len(s.fields())


def test_view_taken_before_a_run_sees_its_writes():
    rng = np.random.default_rng(1)
    s = kinds_set()
    values = fill(s, rng)
    views = {name: s[name] for name in s.fields()}
    step = compiled(KINDS_PROGRAM, "step")
    step.bind("ps", s)
    step.run()
    expected = touched(values)
    for name, view in views.items():
        np.testing.assert_array_equal(view, expected[name], err_msg=name)
    step.run()
    twice = touched(expected)
    for name, view in views.items():
        np.testing.assert_array_equal(view, twice[name], err_msg=name)


def test_writes_to_a_view_are_what_the_next_run_reads():
    rng = np.random.default_rng(2)
    s = kinds_set()
    fill(s, rng)
    step = compiled(KINDS_PROGRAM, "step")
    step.bind("ps", s)
    step.run()
    views = {name: s[name] for name in s.fields()}
    # New values written through the views (in place, no rebinding) between runs.
    new = {
        "a": rng.standard_normal(N),
        "i": rng.integers(-50, 50, N).astype(np.int32),
        "b": rng.integers(0, 2, N).astype(bool),
        "c": rng.standard_normal(N) - 2j,
        "v": rng.standard_normal((N, 3)),
        "M": rng.standard_normal((N, 2, 3)),
    }
    for name, value in new.items():
        views[name][...] = value
    views["a"][2] = 40.0  # one element through item assignment
    new["a"][2] = 40.0
    step.run()
    assert_fields(s, touched(new))


def test_view_outlives_the_set():
    rng = np.random.default_rng(3)
    s = kinds_set()
    values = fill(s, rng)
    views = {name: s[name] for name in s.fields()}
    del s
    gc.collect()
    for name, view in views.items():
        np.testing.assert_array_equal(view, values[name], err_msg=name)
    views["v"][1] = [7.0, 8.0, 9.0]  # still writable storage
    np.testing.assert_array_equal(views["v"][1], [7.0, 8.0, 9.0])
    np.testing.assert_array_equal(views["v"][0], values["v"][0])


def test_bound_set_kept_alive_by_the_function():
    rng = np.random.default_rng(4)
    s = kinds_set()
    values = fill(s, rng)
    a = s["a"]
    step = compiled(KINDS_PROGRAM, "step")
    step.bind("ps", s)
    del s
    gc.collect()
    step.run()
    np.testing.assert_array_equal(a, 2.0 * values["a"] + 1.0)


def edge_sets(connectivity):
    qs = simit.Set(4)
    qs.add_field("w", float)[:] = [1.0, 2.0, 3.0, 4.0]
    es = simit.Set(endpoints=(qs, qs), connectivity=connectivity)
    es.add_field("s", float)
    return qs, es


def test_endpoints_view_and_use():
    conn = np.array([[0, 1], [3, 2], [2, 2], [1, 0]])  # int64, as numpy makes it
    qs, es = edge_sets(conn)
    assert len(es) == 4
    ends = es.endpoints
    assert ends.shape == (4, 2) and ends.dtype == np.int32
    np.testing.assert_array_equal(ends, conn)
    assert not ends.flags.writeable
    with pytest.raises(ValueError):
        ends[0, 0] = 3
    f = compiled(EDGES_PROGRAM, "ends")
    f.bind("qs", qs)
    f.bind("es", es)
    s = es["s"]
    f.run()
    w = np.array([1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(s, w[conn[:, 0]] + 10.0 * w[conn[:, 1]])
    # The endpoints view, like the fields', outlives its set.
    del es, f
    gc.collect()
    np.testing.assert_array_equal(ends, conn)


def test_endpoint_sets_may_differ():
    a = simit.Set(2)
    b = simit.Set(3)
    e = simit.Set(endpoints=(a, b, b), connectivity=np.array([[1, 2, 0], [0, 0, 2]], np.int32))
    np.testing.assert_array_equal(e.endpoints, [[1, 2, 0], [0, 0, 2]])
    # Index 2 is in range for b (3 elements) but not for a (2 elements).
    with pytest.raises(simit.Error, match=r"\b2\b"):
        simit.Set(endpoints=(a, b, b), connectivity=np.array([[2, 0, 0]]))


@pytest.mark.parametrize(
    "connectivity, pattern",
    [
        (np.array([[0, 1], [1, 4]]), r"\b4\b"),  # 4 is past the 4 elements 0..3
        (np.array([[0, 1], [-1, 2]]), r"-1\b"),
        (np.array([[0, 1, 2]]), r"(?i)(column|endpoint).*\b3\b"),
        (np.array([0, 1]), r"(?i)(column|endpoint|shape|dimension)"),
        (np.array([[0.5, 1.0]]), r"(?i)int"),
        (np.array([["0", "1"]]), r"(?i)int"),
    ],
    ids=["past_end", "negative", "three_columns", "one_dimensional", "floats", "strings"],
)
def test_connectivity_checks(connectivity, pattern):
    qs = simit.Set(4)
    with pytest.raises(simit.Error) as info:
        simit.Set(endpoints=(qs, qs), connectivity=connectivity)
    message = str(info.value)
    assert re.search(pattern, message), message
