# The module's errors (compile, bind, run time), that the objects still work after each, and
# how a run behaves towards Python: Ctrl-C, the GIL, print.
import os
import re
import signal
import threading
import time

import numpy as np
import pytest

import simit

SPRINGS = """
element Point
  x : vector[3](float);
  m : float;
end

element Spring
  k : float;
end

extern points  : set{Point};
extern springs : set{Spring}(points, points);
extern gravity : vector[3](float);

func pull(inout q : Point)
  q.x = q.x + q.m * gravity;
end

func stretch(inout s : Spring, p : (Point * 2))
  s.k = norm(p(1).x - p(0).x);
end

export func step()
  apply pull to points;
  apply stretch to springs;
end
"""

# An apply over a set inside a scalar loop: each iteration is a statement where a run can
# stop, interpreted or compiled.
SPIN = """
element P
  c : float;
end

extern ps : set{P};

func bump(inout p : P)
  p.c = p.c + 1.0;
end

export func spin(n : int) -> s : float
  for i in 0:n
    apply bump to ps;
    s = s + 1.0;
  end
end
"""


def test_error_classes():
    for cls in (simit.CompileError, simit.BindError, simit.RuntimeError):
        assert issubclass(cls, simit.Error)
    assert issubclass(simit.Error, Exception)


def find(text, token):
    """1-based (line, column) of the first `token` in `text`."""
    before = text[: text.index(token)]
    return before.count("\n") + 1, len(before) - before.rfind("\n")


@pytest.mark.parametrize(
    "source, token, category",
    [
        ("export func f() -> r : float\n  r = 1.0 +\n      q;\nend\n", "q;", "undeclared"),
        ("export func f()\n  x = 1.0 +* 2.0;\nend\n", "*", "syntax"),
        ("export func f()\n  x = 1.0 $ 2.0;\nend\n", "$", "lexical"),
    ],
    ids=["undeclared", "syntax", "lexical"],
)
def test_compile_error_diagnostics(tmp_path, source, token, category):
    line, column = find(source, token)
    with pytest.raises(simit.CompileError) as info:
        simit.Program(source=source)
    diagnostics = info.value.diagnostics
    assert len(diagnostics) >= 1
    d = diagnostics[0]
    assert (d.line, d.column) == (line, column)
    assert d.category == category
    assert isinstance(d.message, str) and d.message
    if category == "undeclared":
        assert "'q'" in d.message

    # From a file: the message is rendered with the file's name and the position.
    path = tmp_path / "broken.sim"
    path.write_text(source)
    with pytest.raises(simit.CompileError) as info:
        simit.Program(path=str(path))
    assert f"broken.sim:{line}:{column}" in str(info.value)
    assert (info.value.diagnostics[0].line, info.value.diagnostics[0].column) == (line, column)


def test_unreadable_program_file(tmp_path):
    missing = tmp_path / "missing.sim"
    with pytest.raises(simit.Error, match="missing.sim"):
        simit.Program(path=str(missing))


def test_unknown_function_then_compile(backend):
    program = simit.Program(source=SPRINGS, backend=backend)
    with pytest.raises(simit.Error, match="nope"):
        program.compile("nope")
    assert program.functions() == ["step"]
    assert sorted(program.compile("step").unbound()) == ["gravity", "points", "springs"]


def springs_sets(with_m=True, x_shape=(3,), x_dtype=float):
    points = simit.Set(3)
    points.add_field("x", x_dtype, shape=x_shape)
    if with_m:
        points.add_field("m", float)[:] = [1.0, 2.0, 3.0]
    springs = simit.Set(endpoints=(points, points), connectivity=np.array([[0, 1], [1, 2]]))
    springs.add_field("k", float)
    return points, springs


def check_step_runs(fn, points, springs):
    """Binds good data and runs `fn`, checking the results against numpy."""
    x = np.arange(9.0).reshape(3, 3)
    points["x"][:] = x
    gravity = np.array([0.0, -1.0, 0.5])
    fn.bind("points", points)
    fn.bind("springs", springs)
    fn.bind("gravity", gravity)
    fn.run()
    m = points["m"]
    expected = x + m[:, None] * gravity
    np.testing.assert_array_equal(points["x"], expected)
    lengths = np.linalg.norm(expected[[1, 2]] - expected[[0, 1]], axis=1)
    np.testing.assert_allclose(springs["k"], lengths, rtol=1e-15)


@pytest.mark.parametrize(
    "problem, names",
    [
        ("missing_field", ("points", "m")),
        ("field_shape", ("points", "x")),
        ("field_dtype", ("points", "x")),
    ],
)
def test_bind_error_for_a_set(backend, problem, names):
    fn = simit.Program(source=SPRINGS, backend=backend).compile("step")
    bad = {
        "missing_field": lambda: springs_sets(with_m=False),
        "field_shape": lambda: springs_sets(x_shape=(2,)),
        "field_dtype": lambda: springs_sets(x_dtype=int),
    }[problem]
    points, springs = bad()
    with pytest.raises(simit.BindError) as info:
        fn.bind("points", points)
        fn.bind("springs", springs)
        fn.bind("gravity", np.zeros(3))
        fn.init()
    problems = info.value.problems
    assert isinstance(problems, list) and problems
    assert all(isinstance(p, str) for p in problems)
    assert any(all(n in p for n in names) for p in problems), problems
    # The same function with good sets.
    check_step_runs(fn, *springs_sets())


@pytest.mark.parametrize("value", [np.zeros(4), np.zeros((3, 1)), 2.0, [1.0, 2.0]])
def test_bind_error_for_a_tensor(backend, value):
    fn = simit.Program(source=SPRINGS, backend=backend).compile("step")
    points, springs = springs_sets()
    fn.bind("points", points)
    fn.bind("springs", springs)
    with pytest.raises(simit.BindError) as info:
        fn.bind("gravity", value)
        fn.init()
    assert any("gravity" in p for p in info.value.problems), info.value.problems
    check_step_runs(fn, points, springs)


def test_unbound_extern_is_an_error(backend):
    fn = simit.Program(source=SPRINGS, backend=backend).compile("step")
    points, springs = springs_sets()
    fn.bind("points", points)
    fn.bind("springs", springs)
    assert fn.unbound() == ["gravity"]
    with pytest.raises(simit.Error, match="gravity"):
        fn.run()
    check_step_runs(fn, points, springs)


def test_runtime_error_out_of_range(tmp_path, backend):
    source = "extern v : vector[3](float);\nexport func f(i : int) -> r : float\n  r = v(i);\nend\n"
    path = tmp_path / "oob.sim"
    path.write_text(source)
    fn = simit.Program(path=str(path), backend=backend).compile("f")
    fn.bind("v", np.array([1.0, 2.0, 3.0]))
    fn.bind("i", 5)
    with pytest.raises(simit.RuntimeError) as info:
        fn.run()
    assert info.value.line == 3
    assert "oob.sim:3" in str(info.value)
    assert "5" in str(info.value)
    fn.bind("i", 1)
    fn.run()
    assert fn.result("r") == 2.0


def test_runtime_error_names_the_element(tmp_path, backend):
    source = (
        "element P\n  k : int;\nend\nextern ps : set{P};\n"
        "func g(inout p : P)\n  p.k = 10 / p.k;\nend\n"
        "export func f()\n  apply g to ps;\nend\n"
    )
    path = tmp_path / "divide.sim"
    path.write_text(source)
    fn = simit.Program(path=str(path), backend=backend).compile("f")
    ps = simit.Set(5)
    k = ps.add_field("k", int)
    k[:] = [1, 2, -3, 0, 4]  # integer division by zero at element 3
    fn.bind("ps", ps)
    with pytest.raises(simit.RuntimeError) as info:
        fn.run()
    message = str(info.value)
    assert info.value.line == 6
    assert "divide.sim:6" in message
    assert re.search(r"element 3\b", message), message
    k[:] = [1, 2, -3, 7, 4]
    fn.run()
    np.testing.assert_array_equal(k, [10, 5, -3, 1, 2])  # truncating division


def spin_function(backend, size=2000):
    fn = simit.Program(source=SPIN, backend=backend).compile("spin")
    ps = simit.Set(size)
    c = ps.add_field("c", float)
    fn.bind("ps", ps)
    return fn, c


def seconds_per_iteration(fn, n=50):
    fn.bind("n", n)
    fn.run()  # a first run compiles what the JIT compiles
    start = time.perf_counter()
    fn.run()
    return (time.perf_counter() - start) / n


def test_ctrl_c_stops_a_run(backend):
    fn, c = spin_function(backend)
    per_iteration = seconds_per_iteration(fn)
    # A run of about 60 s unless Ctrl-C stops it.
    fn.bind("n", int(60.0 / max(per_iteration, 1e-7)))
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            fn.run()
    finally:
        timer.cancel()
        timer.join()
    elapsed = time.perf_counter() - start
    assert elapsed < 10.0, f"the run stopped {elapsed:.1f} s after it began"
    # The same function runs to the end afterwards.
    before = c.copy()
    fn.bind("n", 3)
    fn.run()
    assert fn.result("s") == 3.0
    np.testing.assert_array_equal(c, before + 3.0)


def test_run_releases_the_gil(backend):
    fn, _ = spin_function(backend)
    per_iteration = seconds_per_iteration(fn)
    fn.bind("n", max(10, int(0.5 / max(per_iteration, 1e-7))))  # about half a second
    count = 0
    stop = threading.Event()

    def counter():
        nonlocal count
        while not stop.is_set():
            count += 1

    thread = threading.Thread(target=counter)
    thread.start()
    try:
        time.sleep(0.05)
        before = count
        start = time.perf_counter()
        fn.run()
        elapsed = time.perf_counter() - start
        during = count - before
    finally:
        stop.set()
        thread.join()
    assert elapsed > 0.1
    # Holding the GIL for the whole run would leave the counter where it was.
    assert during > 1000, f"the thread counted {during} times in a {elapsed:.2f} s run"


def test_print_goes_to_sys_stdout(capsys):
    fn = simit.Program(
        source='export func hello(n : int)\n  println "hello ", n;\n  print "bye";\nend\n'
    ).compile("hello")
    fn.bind("n", 42)
    fn.run()
    assert capsys.readouterr().out == "hello 42\nbye"
