"""Pipes a script into `simit repl` and compares stdout+stderr with the expected text."""
import subprocess
import sys

simit, script, expected = sys.argv[1:4]
with open(script) as f:
    result = subprocess.run([simit, "repl"], stdin=f, capture_output=True, text=True, timeout=60)
got = result.stdout + result.stderr
want = open(expected).read()
if result.returncode != 0 or got != want:
    print("exit status", result.returncode)
    print("--- got\n" + got + "--- want\n" + want)
    sys.exit(1)
