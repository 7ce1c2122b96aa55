# A spring network built in Python from numpy arrays alone (no scene file, the program given
# as source=), stepped by simit.Function and checked against numpy: explicit and implicit
# steps, results, the assembled block-CSR matrix, binding by reference and by copy, the
# executors and the thread count.
import numpy as np
import pytest

import simit

PROGRAM = """
element Point
  x : vector[3](float);
  v : vector[3](float);
  m : float;
end

element Spring
  k : float;
  l0 : float;
end

extern points  : set{Point};
extern springs : set{Spring}(points, points);
extern h       : float;
extern gravity : vector[3](float);
extern cg_tol  : float;
extern cg_max  : int;
extern calls   : vector[2](float);  % written by explicit_step: binding write-back

const eye3 = [1.0, 0.0, 0.0; 0.0, 1.0, 0.0; 0.0, 0.0, 1.0];

func spring_force(s : Spring, p : (Point * 2)) -> f : vector[points](vector[3](float))
  d = p(1).x - p(0).x;
  l = norm(d);
  t = s.k * (l - s.l0) / l * d;
  f(p(0)) = t;
  f(p(1)) = -t;
end

func spring_stiffness(s : Spring, p : (Point * 2))
    -> K : matrix[points,points](matrix[3,3](float))
  d = p(1).x - p(0).x;
  l = norm(d);
  u = d / l;
  Ks = s.k * (u * u');
  K(p(0), p(0)) = -Ks;
  K(p(1), p(1)) = -Ks;
  K(p(0), p(1)) = Ks;
  K(p(1), p(0)) = Ks;
end

func spring_energy(s : Spring, p : (Point * 2)) -> e : vector[points](float)
  l = norm(p(1).x - p(0).x);
  w = 0.5 * s.k * (l - s.l0) * (l - s.l0);
  e(p(0)) = 0.5 * w;
  e(p(1)) = 0.5 * w;
end

func one(q : Point) -> o : vector[points](float)
  o(q) = 1.0;
end

func lumped_mass(q : Point) -> M : matrix[points,points](matrix[3,3](float))
  M(q, q) = q.m * eye3;
end

func rhs(f : vector[points](vector[3](float)), q : Point)
    -> b : vector[points](vector[3](float))
  b(q) = q.m * q.v + h * (f(q) + q.m * gravity);
end

func advance(f : vector[points](vector[3](float)), inout q : Point)
  q.v = q.v + h * (f(q) / q.m + gravity);
  q.x = q.x + h * q.v;
end

% Symplectic Euler; the energy is the springs' before the step.
export func explicit_step() -> (f : vector[points](vector[3](float)), energy : float)
  f = map spring_force to springs reduce +;
  e = map spring_energy to springs reduce +;
  ones = map one to points reduce +;
  energy = dot(e, ones);
  apply advance(f) to points;
  calls = calls + [1.0, 0.5]';
end

% Linearised backward Euler: (M - h^2 K) v' = M v + h (f + M g), solved by CG.
export func implicit_step() -> (K : matrix[points,points](matrix[3,3](float)), iterations : int)
  f = map spring_force to springs reduce +;
  K = map spring_stiffness to springs reduce +;
  M = map lumped_mass to points reduce +;
  A = M - (h * h) * K;
  b = map rhs(f) to points reduce +;
  var x = points.v;
  var r = b - A * x;
  var p = r;
  var rr = r' * r;
  while (rr > cg_tol) and (iterations < cg_max)
    Ap = A * p;
    alpha = rr / (p' * Ap);
    x = x + alpha * p;
    r = r - alpha * Ap;
    rr_new = r' * r;
    p = r + (rr_new / rr) * p;
    rr = rr_new;
    iterations = iterations + 1;
  end
  points.v = x;
  points.x = points.x + h * points.v;
end

export func scale(a : vector[2](vector[3](float)), c : float)
    -> (b : vector[2](vector[3](float)), n : int)
  b = c * a;
  n = 7;
end
"""

H = 0.01
RTOL = 1e-12


class Network:
    """A random spring network: every point in at least one spring, no spring twice."""

    def __init__(self, n, seed, extra=3):
        rng = np.random.default_rng(seed)
        self.n = n
        self.x = rng.standard_normal((n, 3)) * 2.0
        self.v = rng.standard_normal((n, 3))
        self.m = rng.uniform(0.5, 1.5, n)
        chain = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)
        others = np.stack([np.repeat(np.arange(n), extra), rng.integers(0, n, n * extra)], 1)
        pairs = np.concatenate([chain, others])
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]
        self.conn = np.unique(np.sort(pairs, axis=1), axis=0).astype(np.int64)
        self.conn = self.conn[rng.permutation(len(self.conn))]  # not sorted: any order
        flip = rng.integers(0, 2, len(self.conn)).astype(bool)
        self.conn[flip] = self.conn[flip][:, ::-1]
        lengths = np.linalg.norm(self.x[self.conn[:, 1]] - self.x[self.conn[:, 0]], axis=1)
        self.k = rng.uniform(50.0, 150.0, len(self.conn))
        self.l0 = lengths * rng.uniform(0.8, 1.2, len(self.conn))
        self.g = np.array([0.0, -9.81, 0.0])

    def sets(self):
        points = simit.Set(self.n)
        points.add_field("x", float, shape=(3,))[:] = self.x
        points.add_field("v", float, shape=(3,))[:] = self.v
        points.add_field("m", float)[:] = self.m
        springs = simit.Set(endpoints=(points, points), connectivity=self.conn)
        springs.add_field("k", float)[:] = self.k
        springs.add_field("l0", float)[:] = self.l0
        return points, springs


def numpy_force_energy(net, x):
    d = x[net.conn[:, 1]] - x[net.conn[:, 0]]
    l = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])
    t = (net.k * (l - net.l0) / l)[:, None] * d
    f = np.zeros_like(x)
    np.add.at(f, net.conn[:, 0], t)
    np.add.at(f, net.conn[:, 1], -t)
    energy = np.sum(0.5 * net.k * (l - net.l0) ** 2)
    return f, energy


def numpy_stiffness(net, x):
    """The dense 3n x 3n stiffness matrix, assembled spring by spring."""
    K = np.zeros((3 * net.n, 3 * net.n))
    for (a, b), k in zip(net.conn, net.k):
        d = x[b] - x[a]
        u = d / np.linalg.norm(d)
        Ks = k * np.outer(u, u)
        for i, j, sign in ((a, a, -1), (b, b, -1), (a, b, 1), (b, a, 1)):
            K[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += sign * Ks
    return K


def bind_network(fn, points, springs, gravity, cg_tol=1e-28, cg_max=200):
    fn.bind("points", points)
    fn.bind("springs", springs)
    fn.bind("h", H)
    fn.bind("gravity", gravity)
    fn.bind("cg_tol", cg_tol)
    fn.bind("cg_max", cg_max)
    fn.bind("calls", np.zeros(2))


def close(actual, expected, rtol=RTOL):
    scale = max(1.0, float(np.max(np.abs(expected))))
    np.testing.assert_allclose(actual, expected, rtol=rtol, atol=rtol * scale)


def test_program_functions(backend):
    program = simit.Program(source=PROGRAM, backend=backend)
    assert sorted(program.functions()) == ["explicit_step", "implicit_step", "scale"]


def test_explicit_steps_match_numpy(backend):
    net = Network(12, seed=5)
    points, springs = net.sets()
    step = simit.Program(source=PROGRAM, backend=backend).compile("explicit_step")
    bind_network(step, points, springs, net.g)
    x, v = net.x.copy(), net.v.copy()
    for _ in range(3):
        step.run()
        f, energy = numpy_force_energy(net, x)
        v = v + H * (f / net.m[:, None] + net.g)
        x = x + H * v
        close(points["x"], x)
        close(points["v"], v)
        result_f = step.result("f")
        assert isinstance(result_f, np.ndarray) and result_f.shape == (net.n, 3)
        close(result_f, f)
        e = step.result("energy")
        assert isinstance(e, float)
        assert e == pytest.approx(energy, rel=RTOL)


def test_implicit_step_and_matrix_match_numpy(backend):
    net = Network(10, seed=6)
    points, springs = net.sets()
    step = simit.Program(source=PROGRAM, backend=backend).compile("implicit_step")
    bind_network(step, points, springs, net.g)
    assert step.unbound() == []
    step.init()
    step.run()

    f, _ = numpy_force_energy(net, net.x)
    K = numpy_stiffness(net, net.x)
    M = np.diag(np.repeat(net.m, 3))
    A = M - H * H * K
    b = (net.m[:, None] * net.v + H * (f + net.m[:, None] * net.g)).ravel()
    v = np.linalg.solve(A, b).reshape(net.n, 3)
    close(points["v"], v)
    close(points["x"], net.x + H * v)

    iterations = step.result("iterations")
    assert isinstance(iterations, int) and 1 <= iterations < 200

    m = step.matrix("K")
    assert m.shape == (3 * net.n, 3 * net.n)
    assert tuple(m.block_shape) == (3, 3)
    indptr, indices, blocks = m
    assert blocks.shape == (len(indices), 3, 3)
    assert len(indptr) == net.n + 1 and indptr[0] == 0 and indptr[-1] == len(indices)
    # The pattern: every point's own block and both blocks of every spring, each once.
    pattern = {(i, int(j)) for i in range(net.n) for j in indices[indptr[i] : indptr[i + 1]]}
    assert len(pattern) == len(indices)
    expected_pattern = {(i, i) for i in range(net.n)}
    expected_pattern |= {(int(a), int(b)) for a, b in net.conn}
    expected_pattern |= {(int(b), int(a)) for a, b in net.conn}
    assert pattern == expected_pattern
    dense = np.zeros_like(K)
    for i in range(net.n):
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            dense[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] = blocks[p]
    close(dense, K)

    try:
        import scipy.sparse
    except ImportError:
        return
    s = m.to_scipy()
    assert isinstance(s, scipy.sparse.bsr_matrix)
    assert s.blocksize == (3, 3) and s.shape == K.shape
    close(s.toarray(), K)


def test_extern_bound_by_reference_and_by_copy(backend):
    net = Network(6, seed=7)
    step = simit.Program(source=PROGRAM, backend=backend).compile("explicit_step")

    # float64, C order: by reference. The program's writes to `calls` come back into the
    # array, and changing `gravity` in place changes what the next run reads.
    points, springs = net.sets()
    gravity = np.array([0.0, -9.81, 0.0])
    calls = np.array([10.0, 20.0])
    bind_network(step, points, springs, gravity)
    step.bind("calls", calls)
    step.run()
    np.testing.assert_array_equal(calls, [11.0, 20.5])
    gravity[1] = 3.0
    v_before = points["v"].copy()
    x_before = points["x"].copy()
    step.run()
    np.testing.assert_array_equal(calls, [12.0, 21.0])
    f, _ = numpy_force_energy(net, x_before)
    close(points["v"], v_before + H * (f / net.m[:, None] + [0.0, 3.0, 0.0]))

    # A strided array and a float32 array: copies taken at bind time. Changing them later
    # changes nothing; the program's writes stay in the binding's copy.
    points, springs = net.sets()
    base = np.zeros(6)
    strided = base[::2]
    strided[:] = [0.0, -9.81, 0.0]
    calls32 = np.array([10.0, 20.0], dtype=np.float32)
    bind_network(step, points, springs, strided)
    step.bind("calls", calls32)
    strided[1] = 3.0
    step.run()
    np.testing.assert_array_equal(calls32, [10.0, 20.0])
    f, _ = numpy_force_energy(net, net.x)
    close(points["v"], net.v + H * (f / net.m[:, None] + net.g))

    # A list is a copy too.
    points, springs = net.sets()
    glist = [0.0, -9.81, 0.0]
    bind_network(step, points, springs, glist)
    glist[1] = 3.0
    step.run()
    close(points["v"], net.v + H * (f / net.m[:, None] + net.g))


def test_parameters_and_results(backend):
    fn = simit.Program(source=PROGRAM, backend=backend).compile("scale")
    assert sorted(fn.unbound()) == ["a", "c"]
    a = np.arange(6.0).reshape(2, 3) - 2.5
    fn.bind("a", a)
    fn.bind("c", 2.5)
    assert fn.unbound() == []
    fn.run()
    b = fn.result("b")
    assert isinstance(b, np.ndarray) and b.shape == (2, 3)
    np.testing.assert_array_equal(b, 2.5 * a)
    n = fn.result("n")
    assert isinstance(n, int) and n == 7

    # A result bound by reference receives the run's value ...
    out = np.zeros((2, 3))
    fn.bind("b", out)
    fn.bind("c", -1.0)
    fn.run()
    np.testing.assert_array_equal(out, -a)
    # ... and the parameter array by reference is read at every run.
    a[0, 0] = 100.0
    fn.run()
    np.testing.assert_array_equal(out, -a)

    # A result bound as float32 is a copy: the array stays as it was, result() has the value.
    out32 = np.full((2, 3), 9.0, dtype=np.float32)
    fn.bind("b", out32)
    fn.bind("c", 3.0)
    fn.run()
    np.testing.assert_array_equal(out32, np.full((2, 3), 9.0))
    np.testing.assert_array_equal(fn.result("b"), 3.0 * a)

    # A nested list for the blocked parameter: a copy.
    fn.bind("a", [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    fn.run()
    np.testing.assert_array_equal(fn.result("b"), 3.0 * np.arange(1.0, 7.0).reshape(2, 3))


def run_big(backend, threads, n=20000):
    """One implicit and one explicit step of a network big enough for the JIT's threads to
    split its maps and solver loops (the interpreter runs on one thread whatever the count:
    a smaller one does there)."""
    net = Network(n, seed=8, extra=2)
    points, springs = net.sets()
    program = simit.Program(source=PROGRAM, backend=backend, threads=threads)
    implicit = program.compile("implicit_step")
    bind_network(implicit, points, springs, net.g, cg_tol=0.0, cg_max=15)
    implicit.run()
    indptr, indices, blocks = implicit.matrix("K")
    explicit = program.compile("explicit_step")
    bind_network(explicit, points, springs, net.g)
    explicit.run()
    return {
        "x": points["x"].copy(),
        "v": points["v"].copy(),
        "f": explicit.result("f"),
        "energy": np.float64(explicit.result("energy")),
        "K": blocks.copy(),
        "indices": indices.copy(),
    }


def test_threads_do_not_change_the_bits(backend):
    n = 20000 if backend == "jit" else 4000
    one = run_big(backend, 1, n)
    three = run_big(backend, 3, n)
    for name in one:
        assert one[name].tobytes() == three[name].tobytes(), name


def test_interpreter_and_jit_agree():
    from conftest import require_backend

    require_backend("jit")
    results = [run_big(b, 2, 8000) for b in ("interpreter", "jit")]
    for name in results[0]:
        assert results[0][name].tobytes() == results[1][name].tobytes(), name
