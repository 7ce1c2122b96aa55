// `simit dap` on the fem example's cube block: a conditional breakpoint on one element, the
// mapped frame's element and endpoints, stepping into edge_matrix and out, locals, a 3x3
// tensor and a paged set field, evaluate; every expected value comes from `simit debug`.
import assert from 'node:assert/strict';
import {test} from 'node:test';

import {components, fem_sim, parse_stop_line, tensor_components, terminal, timeout_ms, with_session} from './dap_session.mjs';

const scene = 'fem_cube.toml';
const test_timeout = {
  timeout: 8 * timeout_ms
};

// The terminal debugger at the same stops the DAP session makes: the breakpoint on line 71
// for element 17, a step into edge_matrix, a finish back to tet_force (F now assigned).
const oracle = terminal(scene, [
  'break fem.sim:71 if t == 17',
  'run',
  'backtrace',
  'step',
  'finish',
  'print F',
  'print det(F)',
  'print mu',
  'print t',
  'print t.W',
  'print cg_tol',
  'print verts.x(3)',
  'print verts.x(4)',
  'print verts.x(26)',
  'up',
  'print t',
  'print lambda',
]);
const block = (command) => oracle.blocks.find((b) => b.command === command);

// "map tet_force to tets, element 17, endpoints verts[4 3 7 16] (fem.sim:164)"
const map_line = block('backtrace').lines.find((l) => l.trim().startsWith('map tet_force'));
const map_match = /element (\d+), endpoints verts\[([\d ]+)\]/.exec(map_line);
const element = map_match[1];
const endpoints = map_match[2].split(' ');
const step_in_stop = parse_stop_line(block('step').lines[0]);  // edge_matrix at fem.sim:29

test('the oracle is the issue\'s stop: element 17, endpoints 4 3 7 16, edge_matrix line 29', () => {
  assert.equal(element, '17');
  assert.deepEqual(endpoints, ['4', '3', '7', '16']);
  assert.equal(step_in_stop.func, 'edge_matrix');
  assert.equal(step_in_stop.line, 29);
});

// The frame's element and map line may be in its name or in other fields (a label frame
// included); the numbers must be exactly the terminal's.
function assert_mapped_frame(stack, frame) {
  const index = stack.indexOf(frame);
  const nearby =
      [frame, ...stack.slice(index + 1, index + 2).filter((f) => f.presentationHint === 'label')];
  const text = JSON.stringify(nearby);
  assert.match(frame.name, /^tet_force\b/, JSON.stringify(frame));
  assert.match(text, new RegExp(`element ${element}\\b`), `no "element ${element}" in ${text}`);
  const ends = new RegExp(`endpoints[^\\d\\]]*\\[?${endpoints.join('[ ,]+')}\\b`);
  assert.match(text, ends, `no endpoints ${endpoints.join(' ')} in ${text}`);
}

test('conditional breakpoint, step in and out, variables, evaluate', test_timeout, async (t) => {
  await with_session(async (s) => {
    let answer;
    await s.launch({program: scene}, async () => {
      answer = await s.req(
          'setBreakpoints',
          {source: {path: fem_sim}, breakpoints: [{line: 71, condition: 't == 17'}]});
    });

    await t.test('the breakpoint is verified at line 71', () => {
      assert.equal(answer.breakpoints.length, 1);
      const [bp] = answer.breakpoints;
      assert.equal(bp.verified, true, JSON.stringify(bp));
      assert.equal(bp.line, 71);
      assert.equal(typeof bp.id, 'number', JSON.stringify(bp));
    });

    await t.test(
        '1. stops with reason breakpoint in tet_force, element 17, endpoints 4 3 7 16',
        async () => {
          const stop = await s.stopped('breakpoint');
          assert.equal(stop.body.threadId, 1);
          const {threads} = await s.req('threads');
          assert.deepEqual(threads.map((th) => th.id), [1]);
          const stack = await s.stack();
          const frames = stack.filter((f) => f.presentationHint !== 'label');
          assert_mapped_frame(stack, frames[0]);
          assert.equal(frames[0].line, 71);
          assert.match(frames[0].source.path, /fem\.sim$/);
          assert.equal(typeof frames[0].column, 'number');
          assert.equal(frames.length, 2, JSON.stringify(frames));
          assert.match(frames[1].name, /^step\b/);
          assert.equal(frames[1].line, 164);
        });

    await t.test('2. stepIn enters edge_matrix, stepOut returns to tet_force', async () => {
      await s.req('stepIn', {threadId: 1});
      await s.stopped('step');
      let frames = await s.frames();
      assert.match(frames[0].name, new RegExp(`^${step_in_stop.func}\\b`), JSON.stringify(frames));
      assert.equal(frames[0].line, step_in_stop.line);
      assert.equal(frames.length, 3, JSON.stringify(frames));
      assert.match(frames[1].name, /^tet_force\b/);
      assert.equal(frames[1].line, 71);
      assert.equal(frames[2].line, 164);

      await s.req('stepOut', {threadId: 1});
      await s.stopped('step');
      const stack = await s.stack();
      frames = stack.filter((f) => f.presentationHint !== 'label');
      assert.equal(frames.length, 2, JSON.stringify(frames));
      assert_mapped_frame(stack, frames[0]);
      assert.equal(frames[0].line, 71);
    });

    await t.test('3. Locals: scalars as print shows them, F (3x3) by component', async () => {
      const [top] = await s.frames();
      const {scopes} = await s.req('scopes', {frameId: top.id});
      for (const name of ['Locals', 'Globals', 'Sets']) {
        assert.ok(
            scopes.some((sc) => sc.name === name), `no scope ${name}: ${JSON.stringify(scopes)}`);
      }
      const locals = await s.variables((await s.scope(top.id, 'Locals')).variablesReference);
      const local = (name) => {
        const v = locals.find((x) => x.name === name);
        assert.ok(v, `no local ${name} in ${JSON.stringify(locals)}`);
        return v;
      };
      assert.equal(local('mu').value, oracle.value('mu'));
      assert.equal(local('t').value, oracle.value('t'));
      const F = local('F');
      assert.ok(F.variablesReference > 0, `F is not expandable: ${JSON.stringify(F)}`);
      assert.deepEqual(await tensor_components(s, F), components(oracle.value('F')));

      const globals = await s.variables((await s.scope(top.id, 'Globals')).variablesReference);
      const cg_tol = globals.find((x) => x.name === 'cg_tol');
      assert.ok(cg_tol, `no cg_tol in Globals: ${JSON.stringify(globals)}`);
      assert.equal(cg_tol.value, oracle.value('cg_tol'));
    });

    await t.test('3. Sets: verts has its fields, verts.x is paged by element', async () => {
      const [top] = await s.frames();
      const sets = await s.variables((await s.scope(top.id, 'Sets')).variablesReference);
      assert.deepEqual(
          sets.map((v) => v.name).filter((n) => n === 'verts' || n === 'tets').sort(),
          ['tets', 'verts'], JSON.stringify(sets));
      const verts = sets.find((v) => v.name === 'verts');
      const fields = await s.variables(verts.variablesReference);
      for (const name of ['x', 'v', 'm', 'pinned']) {
        assert.ok(
            fields.some((f) => f.name === name), `verts lacks ${name}: ${JSON.stringify(fields)}`);
      }
      const x = fields.find((f) => f.name === 'x');
      assert.ok(x.variablesReference > 0, JSON.stringify(x));
      if (x.indexedVariables !== undefined)
        assert.equal(x.indexedVariables, 27);
      else
        assert.equal((await s.variables(x.variablesReference)).length, 27);

      const page = await s.variables(x.variablesReference, {filter: 'indexed', start: 3, count: 2});
      assert.equal(page.length, 2, JSON.stringify(page));
      const last =
          await s.variables(x.variablesReference, {filter: 'indexed', start: 26, count: 1});
      assert.equal(last.length, 1, JSON.stringify(last));
      const cases = [[page[0], 3], [page[1], 4], [last[0], 26]];
      for (const [child, i] of cases) {
        assert.match(child.name, new RegExp(`^\\[?${i}\\]?$`), JSON.stringify(child));
        assert.ok(child.variablesReference > 0, `verts.x[${i}] is not expandable`);
        assert.deepEqual(
            await tensor_components(s, child), components(oracle.value(`verts.x(${i})`)),
            `verts.x[${i}]`);
      }
    });

    await t.test('4. evaluate det(F) equals the terminal\'s print det(F)', async () => {
      const frames = await s.frames();
      const det = await s.evaluate('det(F)', frames[0].id);
      assert.ok(det.success, JSON.stringify(det));
      assert.equal(det.body.result, oracle.value('det(F)'));
      const hover = await s.evaluate('t.W', frames[0].id, 'hover');
      assert.ok(hover.success, JSON.stringify(hover));
      assert.equal(hover.body.result, oracle.value('t.W'));
      // In the caller's frame `t` does not exist and `lambda` is step's own.
      const outer = await s.evaluate('t', frames[1].id);
      assert.equal(outer.success, false, JSON.stringify(outer));
      assert.match(JSON.stringify(outer), /undeclared variable or constant 't'/);
      const lambda = await s.evaluate('lambda', frames[1].id);
      assert.equal(lambda.body?.result, oracle.value('lambda'), JSON.stringify(lambda));
    });

    await t.test('continue runs to the end: exited 0, then terminated', async () => {
      await s.req('continue', {threadId: 1});
      const exited = await s.next('exited');
      assert.equal(exited.body.exitCode, 0);
      const terminated = await s.next('terminated');
      assert.ok(terminated.order > exited.order);
    });
  });
});

test('breakpoints on lines without code are unverified, with a message', test_timeout, async () => {
  const where = terminal(scene, ['break fem.sim:70']).blocks[0].lines[0];  // "... fem.sim:71"
  const moved_to = Number(/:(\d+)$/.exec(where)[1]);
  await with_session(async (s) => {
    let answer;
    await s.launch({program: scene}, async () => {
      answer = await s.req('setBreakpoints', {
        source: {path: fem_sim},
        breakpoints: [{line: 78}, {line: 79}, {line: 9999}, {line: 70}],
      });
    });
    const bps = answer.breakpoints;
    assert.equal(bps.length, 4, JSON.stringify(answer));
    for (const bp of bps.slice(0, 3)) {
      assert.equal(bp.verified, false, JSON.stringify(bp));
      assert.equal(typeof bp.message, 'string', JSON.stringify(bp));
      assert.ok(bp.message.length > 0, JSON.stringify(bp));
    }
    assert.equal(bps[3].verified, true, JSON.stringify(bps[3]));
    assert.equal(bps[3].line, moved_to);
    await s.stopped('breakpoint');
    assert.equal((await s.frames())[0].line, moved_to);
  });
});

test('a condition that is not a bool leaves the breakpoint unverified', test_timeout, async () => {
  const said = terminal(scene, ['break fem.sim:71 if t']);  // "... of type Tet, not bool."
  const message = said.stdout + said.stderr;
  await with_session(async (s) => {
    let answer;
    await s.launch({program: scene}, async () => {
      answer = await s.req(
          'setBreakpoints', {source: {path: fem_sim}, breakpoints: [{line: 71, condition: 't'}]});
    });
    const [bp] = answer.breakpoints;
    assert.equal(bp.verified, false, JSON.stringify(bp));
    assert.match(message, /not bool/);
    assert.match(bp.message ?? '', /not bool/, JSON.stringify(bp));
    const exited = await s.next('exited');
    assert.equal(exited.body.exitCode, 0);
  });
});

test('function breakpoints: conditional, and on the third hit', test_timeout, async () => {
  // The third call of tet_force, as the terminal reaches it with two continues.
  const third = terminal(scene, ['break tet_force', 'run', 'continue', 'continue'])
                    .blocks.filter((b) => b.command === 'continue')
                    .at(-1);
  const third_element =
      parse_stop_line(third.lines.find((l) => /^Breakpoint \d+, /.test(l))).element;
  await with_session(async (s) => {
    let answer;
    await s.launch({program: scene}, async () => {
      answer = await s.req(
          'setFunctionBreakpoints', {breakpoints: [{name: 'tet_force', condition: 't == 17'}]});
    });
    assert.equal(answer.breakpoints[0].verified, true, JSON.stringify(answer));
    await s.stopped('function breakpoint');
    const stack = await s.stack();
    assert_mapped_frame(stack, stack.filter((f) => f.presentationHint !== 'label')[0]);
  });
  await with_session(async (s) => {
    await s.launch({program: scene}, async () => {
      await s.req(
          'setFunctionBreakpoints', {breakpoints: [{name: 'tet_force', hitCondition: '3'}]});
    });
    await s.stopped('function breakpoint');
    const [top] = await s.frames();
    const t = await s.evaluate('t', top.id);
    assert.equal(t.body?.result, `tets[${third_element}]`, JSON.stringify(t));
  });
  await with_session(async (s) => {
    let answer;
    await s.launch({program: scene}, async () => {
      answer = await s.req('setFunctionBreakpoints', {breakpoints: [{name: 'nosuch'}]});
    });
    assert.equal(answer.breakpoints[0].verified, false, JSON.stringify(answer));
    assert.ok(answer.breakpoints[0].message, JSON.stringify(answer));
  });
});

test('a data breakpoint is a watch: tets.W[17] written by rest_shape', test_timeout, async () => {
  const watch = terminal(scene, ['watch tets.W[17]', 'run', 'print t.W']);
  const run = watch.blocks.find((b) => b.command === 'run').lines;
  const stop = parse_stop_line(run.find((l) => / just after /.test(l)));
  await with_session(async (s) => {
    await s.launch({program: scene}, async () => {
      const info = await s.req('dataBreakpointInfo', {name: 'verts.x[3]'});
      assert.equal(info.dataId, 'verts.x[3]', JSON.stringify(info));
      const answer = await s.req('setDataBreakpoints', {breakpoints: [{dataId: 'tets.W[17]'}]});
      assert.equal(answer.breakpoints[0].verified, true, JSON.stringify(answer));
    });
    await s.stopped('data breakpoint');
    const stack = await s.stack();
    const top = stack.filter((f) => f.presentationHint !== 'label')[0];
    assert.match(top.name, new RegExp(`^${stop.func}\\b`));
    assert.match(
        JSON.stringify(top) + JSON.stringify(stack[1]), new RegExp(`element ${stop.element}\\b`));
    assert.equal(top.line, stop.line);
    const value = await s.evaluate('t.W', top.id);
    assert.equal(value.body?.result, watch.value('t.W'), JSON.stringify(value));
  });
});
