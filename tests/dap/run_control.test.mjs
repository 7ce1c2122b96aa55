// `simit dap`'s session and run control: capabilities, a .sim function with arguments and its
// output, stopOnEntry and stepping, the NaN trap and run-time errors as exceptions, pause in
// a long run, the end of a run, disconnect, --float32, and requests it does not know.
import assert from 'node:assert/strict';
import {mkdtempSync, readFileSync, rmSync, writeFileSync} from 'node:fs';
import {tmpdir} from 'node:os';
import {join} from 'node:path';
import {test} from 'node:test';

import {components, debugger_dir, fem_sim, parse_stop_line, terminal, timeout_ms, with_session} from './dap_session.mjs';

const test_timeout = {
  timeout: 8 * timeout_ms
};
const calls = {
  program: 'calls.sim',
  function: 'main',
  args: ['3.0', '4.0']
};

test(
    'initialize, launch of a .sim function, its output, exited then terminated', test_timeout,
    async () => {
      // What the program prints: the lines of the terminal's run between the command and its
      // result lines (`println c` writes "5").
      const run = terminal('calls.sim', ['run main 3.0 4.0']).blocks[0].lines;
      assert.equal(run[0], '5');
      await with_session(async (s) => {
        await s.launch(calls);
        const caps = s.capabilities;
        for (const name
                 of ['supportsConfigurationDoneRequest', 'supportsFunctionBreakpoints',
                     'supportsConditionalBreakpoints', 'supportsHitConditionalBreakpoints',
                     'supportsEvaluateForHovers', 'supportsDataBreakpoints',
                     'supportsTerminateRequest']) {
          assert.equal(caps[name], true, `${name} in ${JSON.stringify(caps)}`);
        }
        const nan = (caps.exceptionBreakpointFilters ?? []).find((f) => f.filter === 'nan');
        assert.ok(
            nan && typeof nan.label === 'string' && nan.label.length > 0,
            JSON.stringify(caps.exceptionBreakpointFilters));
        assert.ok(
            s.initialized.order > s.launch_response.order,
            'the initialized event came before the launch response');

        const exited = await s.next('exited');
        assert.equal(exited.body.exitCode, 0);
        const terminated = await s.next('terminated');
        assert.ok(terminated.order > exited.order, 'terminated came before exited');
        assert.ok(
            s.output('stdout').split(/\r?\n/).includes(run[0]),
            `no line "${run[0]}" in the stdout output: ${JSON.stringify(s.output('stdout'))}`);

        const response = await s.raw('disconnect', {});
        assert.ok(response.success, JSON.stringify(response));
        assert.deepEqual(await s.exit_status(), {code: 0, signal: null});
      });
    });

test(
    'stopOnEntry, next, function breakpoints set while stopped, stepOut', test_timeout,
    async () => {
      const entry = terminal('calls.sim', ['break main', 'run main 3.0 4.0', 'next']).blocks;
      const entry_line = parse_stop_line(entry[1].lines[0]).line;       // main at calls.sim:13
      const next_line = Number(/^(\d+)\t/.exec(entry[2].lines[0])[1]);  // 14
      // A stepOut from the first square call meets the breakpoint in the second one (as gdb's
      // finish does); with the breakpoint gone it returns to hypot.
      const oracle = terminal(
          'calls.sim',
          ['break square', 'run main 3.0 4.0', 'print x', 'finish', 'print x', 'delete', 'finish']);
      const xs = oracle.blocks.filter((b) => b.command === 'print x').map((b) => b.lines[0]);
      assert.deepEqual(xs, ['x = 3.0', 'x = 4.0']);
      const interrupted = oracle.blocks[3].lines[1];  // "Breakpoint 1, square at calls.sim:4"
      assert.match(interrupted, /^Breakpoint 1, square /);
      const after = parse_stop_line(oracle.blocks.at(-2).lines[1]);  // hypot just after calls.sim:8

      await with_session(async (s) => {
        await s.launch({...calls, stopOnEntry: true});
        await s.stopped('entry');
        let [top] = await s.frames();
        assert.match(top.name, /^main\b/);
        assert.equal(top.line, entry_line);
        assert.match(top.source.path, /calls\.sim$/);

        await s.req('next', {threadId: 1});
        await s.stopped('step');
        [top] = await s.frames();
        assert.equal(top.line, next_line);
      });

      // A breakpoint set while stopped at the entry is reached by continue.
      await with_session(async (s) => {
        await s.launch({...calls, stopOnEntry: true});
        await s.stopped('entry');
        const answer = await s.req('setFunctionBreakpoints', {breakpoints: [{name: 'square'}]});
        assert.equal(answer.breakpoints[0].verified, true, JSON.stringify(answer));
        await s.req('continue', {threadId: 1});
        await s.stopped('function breakpoint');
        let frames = await s.frames();
        assert.deepEqual(frames.map((f) => f.name.split(' ')[0]), ['square', 'hypot', 'main']);
        let x = await s.evaluate('x', frames[0].id);
        assert.equal(`x = ${x.body?.result}`, xs[0], JSON.stringify(x));

        await s.req('stepOut', {threadId: 1});
        await s.stopped('function breakpoint');
        frames = await s.frames();
        assert.deepEqual(frames.map((f) => f.name.split(' ')[0]), ['square', 'hypot', 'main']);
        x = await s.evaluate('x', frames[0].id);
        assert.equal(`x = ${x.body?.result}`, xs[1], JSON.stringify(x));

        await s.req('setFunctionBreakpoints', {breakpoints: []});
        await s.req('stepOut', {threadId: 1});
        await s.stopped('step');
        frames = await s.frames();
        assert.match(frames[0].name, new RegExp(`^${after.func}\\b`));
        assert.equal(frames[0].line, after.line);

        await s.req('continue', {threadId: 1});
        assert.equal((await s.next('exited')).body.exitCode, 0);
        await s.next('terminated');
      });
    });

test(
    '5. the nan exception filter stops where the terminal\'s NaN trap does', test_timeout,
    async () => {
      const transcript = readFileSync(join(debugger_dir, 'nan_trap.expected'), 'utf8').split('\n');
      const trap = transcript.findIndex((l) => l.startsWith('NaN trap'));
      const what = /: (.*)$/.exec(transcript[trap])[1];  // "t.e = nan"
      const stop = parse_stop_line(transcript[trap + 1]);
      const endpoints =
          /endpoints verts\[([\d ]+)\]/.exec(transcript.find((l) => /^\s+apply /.test(l)))[1];
      const vol = transcript.find((l) => l.startsWith('t.vol = ')).slice('t.vol = '.length);

      await with_session(async (s) => {
        await s.launch({program: 'energy_flipped.toml'}, async () => {
          await s.req('setExceptionBreakpoints', {filters: ['nan']});
        });
        const event = await s.stopped('exception');
        const said = `${event.body.text ?? ''} ${event.body.description ?? ''}`;
        assert.ok(said.includes(what), `"${what}" not in ${JSON.stringify(event)}`);
        const stack = await s.stack();
        const frames = stack.filter((f) => f.presentationHint !== 'label');
        assert.match(frames[0].name, new RegExp(`^${stop.func}\\b`), JSON.stringify(frames[0]));
        assert.equal(frames[0].line, stop.line);
        assert.ok(frames[0].source.path.endsWith(stop.file), JSON.stringify(frames[0]));
        const text = JSON.stringify(stack.slice(0, 2));
        assert.match(text, new RegExp(`element ${stop.element}\\b`), text);
        assert.match(text, new RegExp(endpoints.split(' ').join('[ ,]+')), text);
        const value = await s.evaluate('t.vol', frames[0].id);
        assert.equal(value.body?.result, vol, JSON.stringify(value));

        await s.req('continue', {threadId: 1});
        assert.equal((await s.next('exited')).body.exitCode, 0);
        await s.next('terminated');
      });
    });

test('a run-time error stops with reason exception and its message', test_timeout, async () => {
  const dir = mkdtempSync(join(tmpdir(), 'simit-dap-'));
  try {
    const program = join(dir, 'out_of_range.sim');
    writeFileSync(program, [
      '% An index beyond a vector: a run-time error on line 4.',
      'export func main(i : int) -> y : float',
      '  v = [1.0, 2.0, 3.0];',
      '  y = v(i);',
      'end',
      '',
    ].join('\n'));
    const said = terminal(program, ['run main 5'], {cwd: dir}).stderr;
    const message = /runtime error: (.*)/.exec(said)[1];  // "index 5 is out of range ..."
    const line = Number(/in main \((?:.*\/)?out_of_range\.sim:(\d+)\)/.exec(said)[1]);
    assert.equal(line, 4);

    await with_session(async (s) => {
      await s.launch({program, cwd: dir, function: 'main', args: ['5']});
      const event = await s.stopped('exception');
      const text = `${event.body.text ?? ''} ${event.body.description ?? ''}`;
      assert.ok(text.includes(message), `"${message}" not in ${JSON.stringify(event)}`);
      const [top] = await s.frames();
      assert.match(top.name, /^main\b/);
      assert.equal(top.line, line);
      await s.req('continue', {threadId: 1});
      const exited = await s.next('exited');
      assert.notEqual(exited.body.exitCode, 0, 'a run stopped by an error exited 0');
      await s.next('terminated');
    });
  } finally {
    rmSync(dir, {recursive: true, force: true});
  }
});

test(
    '6. pause during a long run stops with reason pause; terminate ends it', test_timeout,
    async () => {
      await with_session(async (s) => {
        await s.launch({program: 'fem_cube.toml', frames: 1000000});
        await new Promise((r) => setTimeout(r, 500));
        assert.equal(
            s.events.some(({event}) => event.event === 'exited'), false,
            'the run of 1000000 frames ended within half a second');
        await s.req('pause', {threadId: 1});
        await s.stopped('pause');
        let frames = await s.frames();
        assert.ok(frames.length > 0);
        assert.ok(frames.at(-1).source.path.endsWith('fem.sim'), JSON.stringify(frames));
        assert.match(frames.at(-1).name, /^(init|step)\b/);

        await s.req('continue', {threadId: 1});
        await new Promise((r) => setTimeout(r, 200));
        await s.req('pause', {threadId: 1});
        await s.stopped('pause');
        frames = await s.frames();
        assert.ok(frames.length > 0);

        await s.req('terminate', {});
        await s.next('terminated');
        const response = await s.raw('disconnect', {});
        assert.ok(response.success, JSON.stringify(response));
        assert.deepEqual(await s.exit_status(), {code: 0, signal: null});
      });
    });

test(
    '7. a scene run to its end: progress output, exited 0, terminated, the process exits 0',
    test_timeout, async () => {
      // "fem_cube.toml: tets 48, verts 27; 1 frames" -> "tets 48, verts 27"
      const run = terminal('fem_cube.toml', ['run']).blocks[0].lines;
      const sizes = /tets \d+, verts \d+/.exec(run[0])[0];
      await with_session(async (s) => {
        await s.launch({program: join(debugger_dir, 'fem_cube.toml'), frames: 2});
        const exited = await s.next('exited');
        assert.equal(exited.body.exitCode, 0);
        const terminated = await s.next('terminated');
        assert.ok(terminated.order > exited.order);
        const out = s.output('stdout');
        assert.ok(
            out.includes(sizes), `no "${sizes}" in the stdout output: ${JSON.stringify(out)}`);
        const response = await s.raw('disconnect', {});
        assert.ok(response.success, JSON.stringify(response));
        assert.deepEqual(await s.exit_status(), {code: 0, signal: null});
      });
    });

test(
    '7. disconnect while stopped at a breakpoint ends the process with status 0', test_timeout,
    async () => {
      await with_session(async (s) => {
        await s.launch({program: 'fem_cube.toml'}, async () => {
          await s.req(
              'setBreakpoints',
              {source: {path: fem_sim}, breakpoints: [{line: 71, condition: 't == 17'}]});
        });
        await s.stopped('breakpoint');
        const response = await s.raw('disconnect', {});
        assert.ok(response.success, JSON.stringify(response));
        assert.deepEqual(await s.exit_status(), {code: 0, signal: null});
      });
    });

test(
    'float32 launches compute in single precision, as simit debug --float32', test_timeout,
    async () => {
      const commands = ['break fem.sim:71 if t == 17', 'run', 'step', 'finish', 'print det(F)'];
      const single = terminal('fem_cube.toml', commands, {flags: ['--float32']}).value('det(F)');
      const double = terminal('fem_cube.toml', commands).value('det(F)');
      assert.notEqual(single, double);
      await with_session(async (s) => {
        await s.launch({program: 'fem_cube.toml', float32: true}, async () => {
          await s.req(
              'setBreakpoints',
              {source: {path: fem_sim}, breakpoints: [{line: 71, condition: 't == 17'}]});
        });
        await s.stopped('breakpoint');
        await s.req('stepIn', {threadId: 1});
        await s.stopped('step');
        await s.req('stepOut', {threadId: 1});
        await s.stopped('step');
        const [top] = await s.frames();
        const det = await s.evaluate('det(F)', top.id);
        assert.equal(det.body?.result, single, JSON.stringify(det));
      });
    });

test('an unknown request gets success false; the session goes on', test_timeout, async () => {
  await with_session(async (s) => {
    await s.launch({...calls, stopOnEntry: true});
    await s.stopped('entry');
    const response = await s.raw('frobnicate', {really: true});
    assert.equal(response.type, 'response');
    assert.equal(response.command, 'frobnicate');
    assert.equal(response.success, false, JSON.stringify(response));
    assert.ok(
        typeof response.message === 'string' && response.message.length > 0,
        JSON.stringify(response));
    const {threads} = await s.req('threads');
    assert.deepEqual(threads.map((t) => t.id), [1]);
  });
});

test('a launch of a missing program fails with a message', test_timeout, async () => {
  await with_session(async (s) => {
    await s.req('initialize', {adapterID: 'simit', linesStartAt1: true, columnsStartAt1: true});
    const response = await s.raw('launch', {program: 'nosuch.toml', cwd: debugger_dir});
    assert.equal(response.success, false, JSON.stringify(response));
    assert.match(JSON.stringify(response), /nosuch\.toml/);
  });
});
