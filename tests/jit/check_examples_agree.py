#!/usr/bin/env python3
"""The examples under the JIT agree with the interpreter: the same scene run both ways for N
frames must write byte-identical final positions and the same per-frame statistics (every
column but the timings), and the JIT must have compiled some of its sites.

usage: check_examples_agree.py SIMIT SCENE.toml OUTDIR FRAMES [SHUFFLE_SEED] [--threads N]
                                [--executor jit|gpu] [--float32]

With SHUFFLE_SEED the JIT runs its maps through the test-only shuffled executor (chunks of a
few elements in a shuffled order: jit/executor.h), which must give the same bits. The JIT
runs on N threads (default 1), which must give the same bits too. With --executor gpu the
compiled maps run through the GPU executor (over host memory where SIMIT_TEST_GPU_EMULATION
is set), some must have been compiled for the GPU, and some of what they wrote must have
stayed on the device ("gpu residency: N writes left on the device"). --float32 runs both in
float32.
"""
import csv
import os
import shutil
import subprocess
import sys

TIMING_COLUMNS = {"ms", "assembly_ms", "solve_ms"}


def run(simit, scene, out, frames, backend, env=None, threads=1, float32=False):
    if os.path.exists(out):
        shutil.rmtree(out)
    os.makedirs(out)
    final = os.path.join(out, "final.csv")
    cmd = [simit, "run", scene, "--frames", str(frames), "--output", out, "--final-csv", final,
           "--executor", backend]
    if float32:
        cmd.append("--float32")
    if backend != "interpreter":
        cmd += ["--jit-stats", "--jit-cache", "off", "--threads", str(threads)]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit(f"{backend}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    stats = [f for f in os.listdir(out) if f.endswith(".csv") and f != "final.csv"]
    rows = []
    if stats:
        with open(os.path.join(out, stats[0])) as f:
            rows = list(csv.DictReader(f))
    with open(final, "rb") as f:
        return f.read(), rows, p.stdout


def main():
    args = sys.argv[1:]
    threads = 1
    backend = "jit"
    float32 = "--float32" in args
    if float32:
        args.remove("--float32")
    if "--executor" in args:
        at = args.index("--executor")
        backend = args[at + 1]
        del args[at:at + 2]
    if "--threads" in args:
        at = args.index("--threads")
        threads = int(args[at + 1])
        del args[at:at + 2]
    sys.argv[1:] = args
    simit, scene, outdir, frames = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
    a_final, a_rows, _ = run(simit, scene, os.path.join(outdir, "interpreter"), frames, "interpreter",
                             float32=float32)
    env = dict(os.environ)
    if len(sys.argv) > 5:
        env["SIMIT_TEST_SHUFFLE_SEED"] = sys.argv[5]
    b_final, b_rows, b_out = run(simit, scene, os.path.join(outdir, backend), frames, backend,
                                 env, threads, float32)
    on_gpu = b_out.count(" compiled for the GPU\n")
    compiled = b_out.count(" compiled\n") + on_gpu
    if backend == "gpu" and on_gpu == 0:
        sys.exit("no site was compiled for the GPU")
    if backend == "gpu":
        # Residency: what the kernels wrote stayed on the device for the next kernel.
        line = next((l for l in b_out.splitlines() if l.startswith("gpu residency: ")), "")
        kept = int(line.split()[2]) if line else 0
        if kept == 0:
            sys.exit(f"no write was left on the device: {line or 'no gpu residency line'}")
    print(b_out[b_out.find("jit traces:"):])
    if compiled == 0:
        sys.exit("the JIT compiled no site")
    if a_final != b_final:
        a_lines, b_lines = a_final.decode().splitlines(), b_final.decode().splitlines()
        for i, (x, y) in enumerate(zip(a_lines, b_lines)):
            if x != y:
                sys.exit(f"final positions differ first at point {i}: {x} (interpreter) vs {y} ({backend})")
        sys.exit("final position files differ in length")
    if len(a_rows) != len(b_rows):
        sys.exit(f"{len(a_rows)} statistics rows interpreted, {len(b_rows)} under {backend}")
    for ra, rb in zip(a_rows, b_rows):
        for k in ra:
            if k not in TIMING_COLUMNS and ra[k] != rb[k]:
                sys.exit(f"frame {ra.get('frame')}: {k} = {ra[k]} (interpreter) vs {rb[k]} ({backend})")
    print(f"{scene}: {frames} frames, final positions and statistics identical; "
          f"{compiled} traces compiled")


if __name__ == "__main__":
    main()
