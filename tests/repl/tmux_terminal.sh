#!/usr/bin/env bash
# Drives `simit repl` on a real terminal under tmux (a ctest): history recall (within a
# session and from the history file of an earlier one), tab completion of commands,
# intrinsics and set.field names, and Ctrl-C.  tmux_terminal.sh SIMIT SOURCE_DIR
set -euo pipefail
simit="$1"
source_dir="$2"
if ! command -v tmux > /dev/null; then
  echo "SKIP: tmux is not installed (scripts/install_deps.sh installs it)"
  exit 77
fi
# A detached server needs no terminal, but some tmux builds refuse an unset or dumb TERM.
case "${TERM:-dumb}" in dumb) export TERM=xterm ;; esac
work=$(mktemp -d)
socket="simit-repl-test-$$"
cleanup() { tmux -L "$socket" kill-server 2> /dev/null || true; rm -rf "$work"; }
trap cleanup EXIT

pane() { tmux -L "$socket" capture-pane -p -t repl; }
keys() { tmux -L "$socket" send-keys -t repl "$@"; }
# Waits until the pane shows the text (or fails after 20 s, printing the pane).
wait_for() {
  for _ in $(seq 200); do
    if pane | grep -qF -- "$1"; then return 0; fi
    sleep 0.1
  done
  echo "FAIL: waited for '$1'; the pane shows:"
  pane
  exit 1
}
start() {
  tmux -L "$socket" new-session -d -s repl -x 150 -y 40 -c "$source_dir" \
    "env HOME='$work' TERM=xterm '$simit' repl"
  wait_for "simit>"
}
quit() {
  keys C-d
  for _ in $(seq 100); do
    tmux -L "$socket" has-session -t repl 2> /dev/null || return 0
    sleep 0.1
  done
  echo "FAIL: the REPL did not leave on Ctrl-D"
  exit 1
}

start
# Command completion: ':sce' + Tab becomes ':scene '.
keys ':sce' Tab 'tests/scene/fem_bar2k.toml' Enter
wait_for "scene tests/scene/fem_bar2k.toml: tets (1151) verts (439)"
# set.field completion: 'verts.pi' + Tab becomes 'verts.pinned'.
keys ':print verts.pi' Tab '[0]' Enter
wait_for "true : bool"
# Intrinsic completion: 'sq' + Tab becomes 'sqrt'.
keys 'sq' Tab '(16.0)' Enter
wait_for "4.0 : float"
# History recall within the session: Up four times brings back ':print verts.pinned[0]'.
keys 'y = 6.0 * 7.0\;' Enter 'y' Enter  # tmux reads a trailing ';' as a separator
wait_for "42.0 : float"
keys Up Up Up Up Enter
for _ in $(seq 100); do
  [ "$(pane | grep -c 'true : bool')" -ge 2 ] && break
  sleep 0.1
done
if [ "$(pane | grep -c 'true : bool')" -lt 2 ]; then
  echo "FAIL: Up x4 did not recall ':print verts.pinned[0]':"
  pane
  exit 1
fi
# Ctrl-C at the prompt drops the line being typed.
keys 'abc' C-c '2.0 + 3.0' Enter
wait_for "5.0 : float"
if pane | grep -q "abc2.0"; then
  echo "FAIL: Ctrl-C did not drop the typed text"
  pane
  exit 1
fi
# Ctrl-C stops a long computation and returns to the prompt with the session intact.
keys ':run init' Enter ':run step 1000' Enter
wait_for "[1/1000] step:"
keys C-c
wait_for "interrupted at examples/fem/fem.sim:"
keys ':print verts.pinned[1]' Enter
for _ in $(seq 100); do
  [ "$(pane | grep -c 'true : bool')" -ge 3 ] && break
  sleep 0.1
done
[ "$(pane | grep -c 'true : bool')" -ge 3 ] || { echo "FAIL: no prompt after Ctrl-C"; pane; exit 1; }
quit
grep -qF 'y = 6.0 * 7.0;' "$work/.simit_history" || {
  echo "FAIL: the history file does not have the session's lines:"
  cat "$work/.simit_history"
  exit 1
}
# A new session recalls the last session's lines from the history file.
start
keys Up
wait_for "simit> :print verts.pinned[1]"  # the last line of the first session
keys C-u
quit
echo "PASS: completion of :scene, verts.pinned and sqrt; history recall in and across sessions;"
echo "      Ctrl-C drops a typed line and stops a running :run"
