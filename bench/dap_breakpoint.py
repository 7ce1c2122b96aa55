#!/usr/bin/env python3
"""Time to a conditional breakpoint on one element of dragon160k: `simit dap` against the
terminal front end (`simit debug`), the same break in the same run, interleaved repeats,
medians. Both include reading the meshes, compiling and running init up to the stop.

  bench/dap_breakpoint.py [--simit build/tools/simit] [--element 150000] [--repeat 3]
"""

import argparse
import json
import os
import statistics
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "examples", "fem", "dragon160k.toml")


def terminal(simit, element):
    """Seconds from start to the terminal debugger's stop line."""
    script = f"break tet_force if t == {element}\nrun 1\nkill\nquit\n"
    start = time.perf_counter()
    proc = subprocess.Popen([simit, "debug", "--echo", SCENE], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    proc.stdin.write(script)
    proc.stdin.flush()
    stopped = None
    for line in proc.stdout:
        if line.startswith("Breakpoint 1, tet_force"):
            stopped = time.perf_counter() - start
    proc.wait()
    if stopped is None:
        raise SystemExit("the terminal debugger did not stop at the breakpoint")
    return stopped


class Client:
    def __init__(self, simit):
        self.proc = subprocess.Popen([simit, "dap"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        self.seq = 0

    def send(self, command, **arguments):
        self.seq += 1
        body = json.dumps({"seq": self.seq, "type": "request", "command": command,
                           "arguments": arguments}).encode()
        self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        self.proc.stdin.flush()

    def until(self, predicate):
        while True:
            header = self.proc.stdout.readline()
            if not header:
                raise SystemExit("simit dap ended early")
            length = int(header.split(b":")[1])
            self.proc.stdout.readline()
            message = json.loads(self.proc.stdout.read(length))
            if predicate(message):
                return message


def dap(simit, element):
    """Seconds from start to the DAP server's stopped event."""
    start = time.perf_counter()
    c = Client(simit)
    c.send("initialize", adapterID="simit")
    c.send("launch", program=SCENE, frames=1)
    c.until(lambda m: m.get("event") == "initialized")
    c.send("setFunctionBreakpoints",
           breakpoints=[{"name": "tet_force", "condition": f"t == {element}"}])
    c.send("configurationDone")
    c.until(lambda m: m.get("event") == "stopped")
    stopped = time.perf_counter() - start
    c.send("disconnect")
    c.proc.wait()
    return stopped


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--simit", default=os.path.join(ROOT, "build", "tools", "simit"))
    parser.add_argument("--element", type=int, default=150000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    times = {"terminal": [], "dap": []}
    for _ in range(args.repeat):
        times["terminal"].append(terminal(args.simit, args.element))
        times["dap"].append(dap(args.simit, args.element))
    t, d = statistics.median(times["terminal"]), statistics.median(times["dap"])
    print(f"dragon160k, break tet_force if t == {args.element}: terminal {t:.2f} s, "
          f"dap {d:.2f} s (medians of {args.repeat}); dap / terminal = {d / t:.2f}")


if __name__ == "__main__":
    main()
