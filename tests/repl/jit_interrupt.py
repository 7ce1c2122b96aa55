"""Ctrl-C under `:set executor jit` stops a compiled loop that never ends (a ctest).

jit_interrupt.py SIMIT SOURCE_DIR

Pipes lines into `simit repl` from SOURCE_DIR: the fem bar scene, then a while loop whose
condition never fails (a solver that does not converge), compiled at its first execution.
Once it has run a while, the process gets a SIGINT, as Ctrl-C sends it. The REPL must report
the interrupt as it does for an interpreted statement, leave its variables as they were
before the input (an interrupted input assigns none of them) and the field the loop writes as
a whole number of iterations left it, then run the next compiled loop and leave cleanly at the
end of its input. Every wait has a timeout, so a loop that never sees the interrupt fails the
test instead of hanging it.
"""
import queue
import re
import signal
import subprocess
import sys
import threading
import time

TIMEOUT = 30  # seconds for any one expected line


def main():
    simit, source_dir = sys.argv[1:3]
    proc = subprocess.Popen([simit, "repl"], cwd=source_dir, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            bufsize=1)
    lines = queue.Queue()
    seen = []

    def read():
        for line in proc.stdout:
            lines.put(line.rstrip("\n"))
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()

    def fail(why):
        proc.kill()
        proc.wait()
        print("FAIL: " + why)
        print("--- output so far\n" + "\n".join(seen))
        sys.exit(1)

    def send(text):
        proc.stdin.write(text + "\n")
        proc.stdin.flush()

    def expect(pattern):
        """The next output line that matches `pattern` (a regular expression), as a match."""
        deadline = time.monotonic() + TIMEOUT
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                fail("no line matching '%s' within %d s" % (pattern, TIMEOUT))
            try:
                line = lines.get(timeout=left)
            except queue.Empty:
                continue
            if line is None:
                fail("the REPL ended before a line matching '%s'" % pattern)
            seen.append(line)
            m = re.fullmatch(pattern, line)
            if m:
                return m

    send(":scene tests/scene/fem_bar2k.toml")
    expect(r"scene tests/scene/fem_bar2k\.toml: .*")
    send(":set executor jit")
    send("w = 0.0 * verts.v;")
    send("rr = 1.0;")
    send("rr")
    expect(r"1\.0 : float")
    # rr grows with w and never reaches 0: only Ctrl-C ends the loop.
    send("while rr > 0.0\n  w = w + verts.v;\n  verts.x = w;\n  rr = w' * w + 1.0;\nend")
    time.sleep(2.0)  # compiled (a few ms) and running
    if proc.poll() is not None:
        fail("the REPL ended while the loop should run")
    proc.send_signal(signal.SIGINT)
    expect(r"interrupted at .*\(what ran so far stays done\)")

    # The input's variables are as before it, as after an interpreted statement interrupted.
    send("rr")
    expect(r"1\.0 : float")
    # Every vertex's position is the same w (v is the same everywhere): the loop stopped
    # between two iterations, not inside its pass, and after at least one.
    send(":print verts.x[0]")
    first = expect(r"\[(\S+), (\S+), (\S+)\] : vector\[3\]\(float\)").groups()
    send(":print verts.x[438]")
    last = expect(r"\[(\S+), (\S+), (\S+)\] : vector\[3\]\(float\)").groups()
    if first != last or first[0] != first[2] or float(first[1]) != 0.0 or float(first[0]) <= 0:
        fail("verts.x is not what whole iterations leave: %s, %s" % (first, last))

    # The session goes on, compiled: a loop that ends.
    send("n = 0;")
    send("while n < 3\n  w = w + verts.v;\n  n = n + 1;\nend")
    send("n")
    expect(r"3 : int")
    proc.stdin.close()
    try:
        status = proc.wait(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        fail("the REPL did not leave at the end of its input")
    if status != 0:
        fail("exit status %d" % status)
    print("PASS: SIGINT stopped a compiled loop between iterations; the session went on")


main()
