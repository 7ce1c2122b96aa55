// The harness of the `simit dap` tests: a DebugClient session that keeps every event in order,
// and the terminal debugger (`simit debug --echo`) run on a script as the independent oracle.
import {DebugClient} from '@vscode/debugadapter-testsupport';
import assert from 'node:assert/strict';
import {spawnSync} from 'node:child_process';
import {existsSync} from 'node:fs';
import {dirname, join, resolve} from 'node:path';
import {fileURLToPath} from 'node:url';

export const repo_root = resolve(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const debugger_dir = join(repo_root, 'tests', 'debugger');
export const fem_sim = join(repo_root, 'examples', 'fem', 'fem.sim');

// SIMIT_BINARY (ctest sets it to the built target); otherwise the build folder's executable,
// which CMake writes to build/tools/simit (build/simit is accepted too).
function find_binary() {
  if (process.env.SIMIT_BINARY) return process.env.SIMIT_BINARY;
  const candidates =
      [join(repo_root, 'build', 'tools', 'simit'), join(repo_root, 'build', 'simit')];
  return candidates.find((p) => existsSync(p)) ?? candidates[0];
}
export const simit_binary = find_binary();

// Generous: the tests share slow machines, and a stop needs the scene's program compiled.
export const timeout_ms = Number(process.env.SIMIT_DAP_TIMEOUT_MS ?? 20000);

// One `simit dap` process driven by a DebugClient. Every message is recorded with one running
// sequence number, so a test can ask for the next event of a kind without racing its arrival,
// and can check the order of responses and events.
export class Session {
  constructor() {
    this.client = new DebugClient(simit_binary, 'dap', 'simit', {cwd: debugger_dir});
    this.client.defaultTimeout = timeout_ms;
    this.events = [];  // {order, event} in arrival order
    this.consumed = new Set();
    this.waiters = [];
    this.order = 0;
    this.stderr = '';
    const emit = this.client.emit.bind(this.client);
    this.client.emit = (name, message) => {
      if (message && message.type === 'event') {
        this.events.push({order: this.order++, event: message});
        this.wake();
      }
      return emit(name, message);
    };
  }

  static async start() {
    const session = new Session();
    await session.client.start();
    const proc = session.client._adapterProcess;
    proc.stderr.on('data', (data) => (session.stderr += data.toString()));
    session.exit = new Promise((resolve) => {
      proc.on('exit', (code, signal) => resolve({code, signal}));
    });
    // 'close' comes once stdout is read to its end: no response can arrive after it.
    session.closed = new Promise((resolve) => proc.on('close', resolve));
    session.closed.then(() => {
      session.is_closed = true;
      session.wake();
    });
    session.exited_process = null;
    session.exit.then((status) => (session.exited_process = status));
    return session;
  }

  wake() {
    const waiters = this.waiters;
    this.waiters = [];
    for (const w of waiters) w();
  }

  // The raw response (success or not) of a request, with the order it arrived in.
  raw(command, args) {
    return new Promise((resolve, reject) => {
      const timer = setTimeout(
          () => reject(new Error(
              `no response to ${describe_request(command, args)} after ` +
              `${timeout_ms} ms${this.stderr_note()}`)),
          timeout_ms);
      this.closed.then(() => {
        clearTimeout(timer);
        const status = JSON.stringify(this.exited_process);
        reject(new Error(
            `simit dap ended (${status}) without answering ` +
            `${describe_request(command, args)}${this.stderr_note()}`));
      });
      this.client.doSend(command, args, (response) => {
        clearTimeout(timer);
        response.order = this.order++;
        resolve(response);
      });
    });
  }

  // The body of a successful response; a failure names the request and the whole response.
  async req(command, args) {
    const response = await this.raw(command, args);
    assert.ok(
        response.success,
        `${describe_request(command, args)} failed: ${JSON.stringify(response)}` +
            this.stderr_note());
    return response.body ?? {};
  }

  // The first event of this kind not yet taken (optionally one that `accept` accepts),
  // waiting for it up to the timeout.
  async next(kind, {accept = () => true, timeout = timeout_ms} = {}) {
    const deadline = Date.now() + timeout;
    for (;;) {
      const found = this.events.find(
          ({order, event}) => !this.consumed.has(order) && event.event === kind && accept(event));
      if (found) {
        this.consumed.add(found.order);
        found.event.order = found.order;
        return found.event;
      }
      const left = deadline - Date.now();
      if (left <= 0 || this.is_closed) {
        const seen = this.events.map(({event}) => event.event).join(', ');
        const why = this.is_closed ? `simit dap ended (${JSON.stringify(this.exited_process)})` :
                                     `${timeout} ms passed`;
        throw new Error(
            `no '${kind}' event: ${why} (events so far: ${seen || 'none'})` + this.stderr_note());
      }
      await new Promise((resolve) => {
        const timer = setTimeout(resolve, left);
        this.waiters.push(() => {
          clearTimeout(timer);
          resolve();
        });
      });
    }
  }

  // The next stopped event, whose reason must be `reason`.
  async stopped(reason, options) {
    const event = await this.next('stopped', options);
    assert.equal(event.body.reason, reason, `stopped event: ${JSON.stringify(event)}`);
    return event;
  }

  // Everything written through output events of this category so far.
  output(category = 'stdout') {
    return this.events.filter(({event}) => event.event === 'output')
        .filter(({event}) => (event.body.category ?? 'console') === category)
        .map(({event}) => event.body.output)
        .join('');
  }

  // initialize, launch, the `initialized` event, `configure` (breakpoints), configurationDone.
  async launch(launch_args, configure = async () => {}) {
    this.capabilities = await this.req('initialize', {
      clientID: 'simit-dap-tests',
      adapterID: 'simit',
      linesStartAt1: true,
      columnsStartAt1: true,
      pathFormat: 'path',
      supportsVariableType: true,
      supportsVariablePaging: true,
    });
    this.launch_response = await this.raw('launch', {cwd: debugger_dir, ...launch_args});
    assert.ok(
        this.launch_response.success,
        `launch failed: ${JSON.stringify(this.launch_response)}${this.stderr_note()}`);
    this.initialized = await this.next('initialized');
    await configure(this);
    await this.req('configurationDone');
  }

  // The real frames of the stopped thread (frames that are only labels left out).
  async frames() {
    const body = await this.req('stackTrace', {threadId: 1});
    return body.stackFrames.filter((f) => f.presentationHint !== 'label');
  }

  // The whole stack as the client received it, labels included.
  async stack() {
    return (await this.req('stackTrace', {threadId: 1})).stackFrames;
  }

  async variables(reference, paging = {}) {
    assert.ok(reference > 0, `variablesReference ${reference} is not expandable`);
    return (await this.req('variables', {variablesReference: reference, ...paging})).variables;
  }

  // The scope of this name in frame `frame_id`.
  async scope(frame_id, name) {
    const {scopes} = await this.req('scopes', {frameId: frame_id});
    const scope = scopes.find((s) => s.name === name);
    assert.ok(scope, `no scope '${name}' in ${JSON.stringify(scopes)}`);
    return scope;
  }

  async evaluate(expression, frame_id, context = 'repl') {
    return this.raw('evaluate', {expression, frameId: frame_id, context});
  }

  // The adapter's exit status once it ends (a failure if it is still running after the timeout).
  async exit_status(timeout = timeout_ms) {
    let timer;
    const late = new Promise((resolve) => (timer = setTimeout(() => resolve(null), timeout)));
    const status = await Promise.race([this.exit, late]);
    clearTimeout(timer);
    assert.ok(status, `simit dap still running ${timeout} ms after the disconnect`);
    return status;
  }

  // Ends the session whatever state it is in: a disconnect, then the process killed if it
  // has not gone.
  async close() {
    if (!this.exited_process) {
      await Promise.race(
          [this.raw('disconnect', {}).catch(() => {}), new Promise((r) => setTimeout(r, 2000))]);
      await Promise.race([this.exit, new Promise((r) => setTimeout(r, 2000))]);
    }
    this.client.stopAdapter();
  }

  stderr_note() {
    return this.stderr ? `\nsimit dap stderr:\n${this.stderr}` : '';
  }
}

function describe_request(command, args) {
  return `request ${command} ${JSON.stringify(args ?? {})}`;
}

// Runs a test body on a fresh session and always closes it.
export async function with_session(body) {
  const session = await Session.start();
  try {
    await body(session);
  } finally {
    await session.close();
  }
}

// ---- the terminal debugger as the oracle --------------------------------------------------

// Runs `simit debug --echo TARGET` (in tests/debugger unless `cwd`) on the commands, and returns
// its transcript: stdout, stderr, and the value of every `print EXPR` (the text after
// "EXPR = "), the output of each command under its echoed line.
export function terminal(target, commands, {cwd = debugger_dir, flags = []} = {}) {
  const run = spawnSync(simit_binary, ['debug', '--echo', ...flags, target], {
    cwd,
    input: commands.join('\n') + '\nquit\n',
    encoding: 'utf8',
    timeout: 120000,
  });
  assert.equal(
      run.status, 0, `simit debug ${target} failed: ${run.error ?? ''}${run.stdout}${run.stderr}`);
  const blocks = [];  // {command, lines}
  for (const line of run.stdout.split('\n')) {
    if (line.startsWith('(sdb) ')) {
      blocks.push({command: line.slice(6), lines: []});
    } else if (blocks.length) {
      blocks.at(-1).lines.push(line);
    }
  }
  const printed = new Map();
  for (const {command, lines} of blocks) {
    if (!command.startsWith('print ')) continue;
    const expr = command.slice(6);
    const line = lines.find((l) => l.startsWith(`${expr} = `));
    if (line) printed.set(expr, line.slice(expr.length + 3));
  }
  const value = (expr) => {
    assert.ok(printed.has(expr), `the terminal printed no value for ${expr}:\n${run.stdout}`);
    return printed.get(expr);
  };
  return {stdout: run.stdout, stderr: run.stderr, blocks, value};
}

// The numbers in a printed tensor, as their text ("[1.0, 2.5e-3; ...]'" -> ["1.0", "2.5e-3"]).
export function components(text) {
  return text.replace(/^\[|\]'?$/g, '').split(/[,;]\s*/).map((s) => s.trim());
}

// The scalars under a tensor variable, in row-major order: its children, or its rows' children
// (a matrix may show rows "[0]".."[2]" or its components directly).
export async function tensor_components(session, variable) {
  const children = await session.variables(variable.variablesReference);
  const values = [];
  for (const child of children) {
    if (child.variablesReference > 0) {
      for (const c of await session.variables(child.variablesReference)) values.push(c.value);
    } else {
      values.push(child.value);
    }
  }
  return values;
}

// A stop's location line as the terminal's transcript writes it, e.g.
// "energy (element 0 of tets) just after tet_energy.sim:31" (after "Breakpoint 1, " if any).
export function parse_stop_line(line) {
  const m =
      /(?:^|, )(\w+)(?: \(element (\d+) of (\w+)\))? (?:at|just after) ([\w.]+):(\d+)$/.exec(line);
  assert.ok(m, `not a stop line: ${line}`);
  return {func: m[1], element: m[2], set: m[3], file: m[4], line: Number(m[5])};
}
