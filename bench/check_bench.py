#!/usr/bin/env python3
"""Benchmark of the frontend: `simit check` on a generated program of about 20,000 lines.

Usage: bench/check_bench.py SIMIT [LINES] [RUNS]. Prints the line count, the median,
minimum and maximum wall time of RUNS runs, and the median CPU time (which a busy machine
inflates less than the wall time). Not a test: the time is only reported."""
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HEADER = """element Node
  x : vector[3](float);
  v : vector[3](float);
  m : float;
end
element Bar
  k : float;
  l0 : float;
end
extern nodes : set{Node};
extern bars : set{Bar}(nodes, nodes);
const up = [0.0, 1.0, 0.0]';
"""

FUNC = """
func force_{i}(b : Bar, p : (Node * 2)) -> f : vector[nodes](vector[3](float))
  d = p(1).x - p(0).x;
  len = norm(d);
  var t = b.k * (len - b.l0) / len * d;
  if len < 1e-12
    t = 0.0 * d;
  elif len > {i}.5
    t = t + 0.5 * up;
  end
  f(p(0)) = t;
  f(p(1)) = -t;
end

export func step_{i}(h : float) -> e : float
  f = map force_{i} to bars reduce +;
  var k = 0;
  var acc = 0.0;
  while k < {n}
    acc = acc + h * dot(nodes.v, nodes.v);
    k = k + 1;
  end
  nodes.v = nodes.v + h * f;
  nodes.x = nodes.x + h * nodes.v;
  e = acc;
end
"""


def program(lines):
    parts = [HEADER]
    i = 0
    while sum(p.count("\n") for p in parts) < lines:
        parts.append(FUNC.format(i=i, n=i % 7 + 1))
        i += 1
    return "".join(parts)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    simit, lines = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 20000
    runs = int(sys.argv[3]) if len(sys.argv) > 3 else 7
    text = program(lines)
    with tempfile.NamedTemporaryFile("w", suffix=".sim", delete=False) as f:
        f.write(text)
        path = f.name
    try:
        times, cpu = [], []
        for _ in range(runs):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            result = subprocess.run([simit, "check", path], capture_output=True, text=True)
            times.append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            if result.returncode != 0:
                sys.exit("simit check rejected the generated program:\n" + result.stderr[:2000])
        print(f"simit check: {text.count(chr(10))} lines, median {statistics.median(times)*1e3:.1f} ms"
              f" (min {min(times)*1e3:.1f}, max {max(times)*1e3:.1f}, {runs} runs);"
              f" CPU time (user + system) median {statistics.median(cpu)*1e3:.1f} ms")
    finally:
        os.unlink(path)


if __name__ == "__main__":
    main()
