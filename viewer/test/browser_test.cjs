// The viewer in a real browser: `wlx viewer` writes a folder with runs, Debian's chromium (driven
// by puppeteer-core) opens viewer.html from file:// with no server, and the test checks that the
// page loads without a console or page error, renders the machine, plays a run, follows drags by
// the WebAssembly IK with the closure met, and shows `wlx ik`'s own message for an unreachable
// target while keeping the last reachable pose. Screenshots go to OUT_DIR/*.png.
//
// Usage: NODE_PATH=<node_modules with puppeteer-core> WLX_CHROMIUM=<chromium> node browser_test.cjs WLX OUT_DIR
// Exit 0 pass, 1 fail, 77 skipped (no chromium).
const { execFileSync, spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');

const [wlx, outDir] = process.argv.slice(2);
const chromium = process.env.WLX_CHROMIUM;
if (!wlx || !outDir) {
  console.error('usage: node browser_test.cjs WLX OUT_DIR');
  process.exit(2);
}
if (!chromium || chromium.endsWith('-NOTFOUND') || !fs.existsSync(chromium)) {
  console.log('viewer_browser: SKIPPED: chromium not found (apt-get install chromium; tools/setup.sh installs it)');
  process.exit(77);
}
const puppeteer = require('puppeteer-core');

let failures = 0;
function check(condition, what, detail = '') {
  console.log(`${condition ? 'ok  ' : 'FAIL'} ${what}${detail ? ': ' + detail : ''}`);
  if (!condition) ++failures;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const maxDifference = (a, b) => Math.max(...Object.keys(a).map((k) => Math.abs(a[k] - b[k])));

// The line `wlx ik` prints on stderr for these inputs (and its exit code).
function cliIk(inputs) {
  const r = spawnSync(wlx, ['ik'], { input: JSON.stringify(inputs), encoding: 'utf8' });
  return { status: r.status, stderr: r.stderr.trim(), stdout: r.stdout };
}

(async () => {
  const folder = path.join(outDir, 'viewer');
  fs.rmSync(outDir, { recursive: true, force: true });
  fs.mkdirSync(outDir, { recursive: true });
  execFileSync(wlx, ['viewer', '--out', folder, 'NH-1', 'ID-1', 'ST-A1+'], { stdio: 'inherit' });
  for (const f of ['viewer.html', 'viewer.js', 'wasm/wlx_excavator.js', 'runs/index.js', 'runs/NH-1.js', 'runs/ID-1.js', 'runs/ST-A1+.js'])
    check(fs.existsSync(path.join(folder, f)), `wlx viewer wrote ${f}`);
  console.log(`sizes: viewer.js ${fs.statSync(path.join(folder, 'viewer.js')).size} B, wasm/wlx_excavator.js ` +
              `${fs.statSync(path.join(folder, 'wasm/wlx_excavator.js')).size} B, runs/NH-1.js ${fs.statSync(path.join(folder, 'runs/NH-1.js')).size} B`);

  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    // SwiftShader: WebGL without a GPU. No --allow-file-access-from-files: the page must work
    // from file:// as a user's browser opens it.
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
  const errors = [];
  async function open(query) {
    const page = await browser.newPage();
    await page.setViewport({ width: 1280, height: 800 });
    page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warning') errors.push(`${query}: console ${m.type()}: ${m.text()}`); });
    page.on('pageerror', (e) => errors.push(`${query}: page error: ${e.message}`));
    page.on('requestfailed', (r) => errors.push(`${query}: request failed: ${r.url()}`));
    const t0 = Date.now();
    await page.goto(`file://${path.resolve(folder)}/viewer.html${query}`);
    await page.evaluate(() => window.wlxViewer.ready);
    console.log(`${query}: loaded and ready in ${Date.now() - t0} ms (page's own count from script start: ` +
                `${(await page.evaluate(() => wlxViewer.api.loadMs())).toFixed(0)} ms)`);
    return page;
  }
  const api = (page, f, ...args) => page.evaluate(f, ...args);

  try {
    // --- a run: renders, plays, scrubs -------------------------------------------------------
    const page = await open('?run=NH-1');
    check((await api(page, () => wlxViewer.api.message())) === '', 'no message after loading NH-1');
    const pixels = await api(page, () => wlxViewer.api.paintedPixels());
    check(pixels.painted > 0.03 * pixels.total, 'the 3D view is not blank', `${pixels.painted} of ${pixels.total} pixels drawn`);
    // The clearance box, found by the module from the generated clearance function: models/excavator.yaml's
    // clearance is frame C (frame 0) of size cxd x cyd x cabin_height = 3 x 3 x 0.5 m.
    const box = (await api(page, () => wlxViewer.api.info())).clearanceBox;
    check(box && box.frame === 0 && box.halfExtents.every((h, i) => Math.abs(h - [1.5, 1.5, 0.25][i]) < 1e-9),
          'the clearance box is the clearance box of the model file', JSON.stringify(box));
    const run = await api(page, () => wlxViewer.api.runInfo());
    check(run && run.samples > 100 && run.plot.columns.length === 2, 'NH-1 loaded with its dependent rates plotted', JSON.stringify(run));
    // The wheels' tracks run through their contact points from the first sample to the last, as
    // `wlx simulate` writes them (x_W<wheel>, y_W<wheel>).
    const simulated = path.join(outDir, 'NH-1');
    execFileSync(wlx, ['simulate', 'NH-1', '--out', simulated], { stdio: 'ignore' });
    const csv = fs.readFileSync(path.join(simulated, 'trajectory.csv'), 'utf8').trim().split('\n').map((l) => l.split(','));
    const column = (name, row) => Number(row[csv[0].indexOf(name)]);
    const tracks = await api(page, () => wlxViewer.api.tracks());
    for (const track of tracks) {
      const first = csv[1], last = csv[csv.length - 1];
      const error = Math.max(Math.abs(track.start[0] - column(`x_W${track.wheel}`, first)), Math.abs(track.start[1] - column(`y_W${track.wheel}`, first)),
                             Math.abs(track.end[0] - column(`x_W${track.wheel}`, last)), Math.abs(track.end[1] - column(`y_W${track.wheel}`, last)));
      check(error < 1e-6 && track.distinct > 100, `wheel ${track.wheel}'s track runs from its first to its last contact point`, `error ${error.toExponential(1)} m`);
    }
    check(tracks.length === 2, 'both wheels have a track');
    const atStart = await api(page, () => wlxViewer.api.coordinates());
    await api(page, () => { wlxViewer.api.setSpeed(2); wlxViewer.api.play(); });
    await sleep(1500);
    const playedTo = await api(page, () => wlxViewer.api.time());
    const whilePlaying = await api(page, () => wlxViewer.api.coordinates());
    check(playedTo > run.start, 'playing advances the time', `t = ${playedTo}`);
    check(maxDifference(atStart, whilePlaying) > 1e-3, 'playing moves the machine', `max change ${maxDifference(atStart, whilePlaying)}`);
    await page.screenshot({ path: path.join(outDir, 'run-playing.png') });
    await api(page, () => wlxViewer.api.lookFromAbove());
    await sleep(200);
    await page.screenshot({ path: path.join(outDir, 'run-tracks-from-above.png') });
    await api(page, () => wlxViewer.api.resetView());
    await api(page, (t) => wlxViewer.api.seek(t), run.end);
    const atEnd = await api(page, () => wlxViewer.api.coordinates());
    const residualAtEnd = await api(page, () => wlxViewer.api.residual());
    check(residualAtEnd < 1e-8, 'the run\'s last pose meets the closure (10 digits stored)', `${residualAtEnd}`);
    await api(page, (t) => wlxViewer.api.seek(t), run.start);
    check(maxDifference(atStart, await api(page, () => wlxViewer.api.coordinates())) === 0, 'seeking back to the start restores the first pose');
    check(maxDifference(atStart, atEnd) > 1e-2, 'the run ends elsewhere than it starts');

    // --- dragging: the WebAssembly IK follows, the closure holds ----------------------------------
    const drags = [
      ['base-move', { z: -0.3, x: 0.2 }],
      ['base-turn', { yaw: 0.1, pitch: 0.05, roll: -0.04 }],
      ['target-F_l', { x: 0.3, z: 0.4 }],
      ['target-F_r', { y: -0.3 }],
      ['ground-W_l', { z: 0.15 }],
    ];
    for (const [handle, delta] of drags) {
      const before = await api(page, () => wlxViewer.api.coordinates());
      const result = await api(page, (h, d) => wlxViewer.api.drag(h, d, 10), handle, delta);
      const after = await api(page, () => wlxViewer.api.coordinates());
      const residual = await api(page, () => wlxViewer.api.residual());
      const moved = Object.keys(after).filter((k) => Math.abs(after[k] - before[k]) > 1e-9);
      check(result.ok && residual < 1e-9 && moved.length >= 2, `drag ${handle} ${JSON.stringify(delta)}`,
            `ok ${result.ok}, residual ${residual.toExponential(2)}, changed ${moved.join(' ')}`);
    }
    // A real mouse drag: pick the right foot's target by its button, grab the gizmo's centre
    // (it moves in the view plane) and pull it 60 px to the right.
    {
      const before = await api(page, () => wlxViewer.api.coordinates());
      await page.click('button[data-handle="target-F_r"]');
      const at = await api(page, () => wlxViewer.api.screenPoint('target-F_r'));
      await page.mouse.move(at.x, at.y);
      await page.mouse.down();
      await page.mouse.move(at.x + 60, at.y, { steps: 12 });
      await page.mouse.up();
      const after = await api(page, () => wlxViewer.api.coordinates());
      const residual = await api(page, () => wlxViewer.api.residual());
      const moved = Object.keys(after).filter((k) => Math.abs(after[k] - before[k]) > 1e-6);
      check(moved.some((k) => /^[xyz]_Fr$/.test(k)) && moved.some((k) => k.startsWith('psi_r')) && residual < 1e-9,
            'a mouse drag of the gizmo moves the target and the leg follows', `changed ${moved.join(' ')}, residual ${residual.toExponential(2)}`);
      await page.screenshot({ path: path.join(outDir, 'mouse-drag.png') });
    }
    // The page's pose is what `wlx ik` computes for the same inputs.
    const inputs = await api(page, () => wlxViewer.api.inputs());
    const names = Object.keys(await api(page, () => wlxViewer.api.coordinates()));
    const request = Object.fromEntries(inputs.map((v, k) => [names[k], v]));
    const cli = cliIk(request);
    const pose = await api(page, () => wlxViewer.api.coordinates());
    const cliPose = JSON.parse(cli.stdout || '{}');
    const dependentNames = names.slice(inputs.length);
    const agreement = Math.max(...dependentNames.map((n) => Math.abs(cliPose[n] - pose[n])));
    check(cli.status === 0 && agreement < 1e-12, 'the dragged pose equals `wlx ik` for the same inputs', `max difference ${agreement}`);
    await page.screenshot({ path: path.join(outDir, 'after-drags.png') });

    // --- unreachable: the CLI's message, the last reachable pose kept -----------------------------
    const reachable = await api(page, () => wlxViewer.api.coordinates());
    const far = { ...request, z_Fl: request.z_Fl + 8 };
    const expected = cliIk(far);
    check(expected.status === 2 && expected.stderr.startsWith('wlx: error: '), '`wlx ik` rejects the far target', expected.stderr);
    const refused = await api(page, () => wlxViewer.api.drag('target-F_l', { z: 8 }, 1));
    check(!refused.ok && refused.message === expected.stderr, 'the page gives the CLI\'s message', refused.message);
    check((await api(page, () => wlxViewer.api.message())) === expected.stderr, 'the message is on screen');
    check(maxDifference(reachable, await api(page, () => wlxViewer.api.coordinates())) === 0, 'the pose stays at the last reachable one');
    await page.screenshot({ path: path.join(outDir, 'unreachable.png') });
    // Dragged in steps past the reach: the pose stops at the last reachable step.
    const stepped = await api(page, () => wlxViewer.api.drag('target-F_l', { z: 8 }, 40));
    const stoppedAt = await api(page, () => wlxViewer.api.coordinates());
    const residualStopped = await api(page, () => wlxViewer.api.residual());
    check(!stepped.ok && stoppedAt.z_Fl > reachable.z_Fl && stoppedAt.z_Fl < reachable.z_Fl + 8 && residualStopped < 1e-9,
          'a drag past the reach stops at the last reachable step', `z_Fl ${reachable.z_Fl} -> ${stoppedAt.z_Fl}, residual ${residualStopped}`);
    // Another branch of the left leg's closed form, picked in the side panel: `wlx ik`'s pose for it.
    {
      await page.select('#branches label:first-child select', '1');
      const q = await api(page, () => wlxViewer.api.inputs());
      const pose = await api(page, () => wlxViewer.api.coordinates());
      const cli = cliIk({ ...Object.fromEntries(q.map((v, k) => [names[k], v])), branch: { leg_l: 1 } });
      const cliPose = JSON.parse(cli.stdout || '{}');
      const difference = Math.max(...dependentNames.map((n) => Math.abs(cliPose[n] - pose[n])));
      check(cli.status === 0 && difference < 1e-12 && Math.abs(pose.psi_l4 - reachable.psi_l4) > 1e-3,
            'branch 1 of the left leg gives `wlx ik`\'s pose for branch 1', `max difference ${difference}, psi_l4 ${pose.psi_l4}`);
      await page.screenshot({ path: path.join(outDir, 'left-leg-branch-1.png') });
      await page.select('#branches label:first-child select', '0');
    }
    const times = await api(page, () => wlxViewer.api.ikTimes());
    times.sort((a, b) => a - b);
    const perSolve = await api(page, () => wlxViewer.api.timeIk(2000));
    console.log(`IK per drag step in the browser: ${(perSolve * 1000).toFixed(1)} us mean over 2000 solves; the drags' ` +
                `${times.length} steps: max ${times[times.length - 1].toFixed(2)} ms (the first, while the engine compiles)`);
    check(perSolve < 5, 'one IK solve takes less than 5 ms in the browser', `${perSolve} ms`);

    // --- an inverse-dynamics run plots torques ----------------------------------------------------
    const dynamics = await open('?run=ID-1');
    const dynamicsRun = await api(dynamics, () => wlxViewer.api.runInfo());
    check(dynamicsRun.plot.columns.every((c) => c.startsWith('tau_')) && dynamicsRun.plot.columns.length === 8, 'ID-1 plots the joint torques', dynamicsRun.plot.columns.join(' '));
    await api(dynamics, (t) => wlxViewer.api.seek(t), (dynamicsRun.start + dynamicsRun.end) / 2);
    await dynamics.screenshot({ path: path.join(outDir, 'dynamics-run.png') });
    // --- the contacts' overlay: arrows as long as the run file's forces, the support polygon ----------
    const runText = fs.readFileSync(path.join(folder, 'runs/ID-1.js'), 'utf8');
    const runFile = JSON.parse(runText.slice(runText.indexOf('registerRun(') + 'registerRun('.length, runText.lastIndexOf(');')));
    const modelInfo = await api(dynamics, () => wlxViewer.api.info());
    const overlay = await api(dynamics, () => wlxViewer.api.forces());
    check(overlay && overlay.shown, 'ID-1 shows the contacts overlay');
    check(JSON.stringify(runFile.contacts) === JSON.stringify(modelInfo.contacts.map((c) => c.name)),
          "the run carries every contact of the model's table, in its order", JSON.stringify(runFile.contacts));
    check(overlay.arrows.length === modelInfo.contacts.length, 'one arrow per contact', `${overlay.arrows.length}`);
    const k = overlay.sampleIndex, col = runFile.columns;
    let worstArrow = 0;
    for (const a of overlay.arrows) {
      const expected = Math.hypot(col['f_x_' + a.name][k], col['f_y_' + a.name][k], col['f_n_' + a.name][k]) * overlay.metresPerNewton;
      worstArrow = Math.max(worstArrow, Math.abs(a.length - expected) / expected);
    }
    check(worstArrow < 1e-12, "each arrow's length is its force from the run file times the shown scale", `relative error ${worstArrow}`);
    const loaded = overlay.arrows.filter((a) => col['f_n_' + a.name][k] > 0).length;
    check(overlay.vertices.length >= 3 && overlay.vertices.length <= loaded, 'the support polygon has at most the loaded contacts as vertices',
          `${overlay.vertices.length} of ${loaded}`);
    // The page's polygon and the runtime's static margin agree on where the CoM is: inside exactly
    // when the margin is positive (the polygon drawn is the one the margin was measured against).
    const inside = (x, y, v) => v.every((p, i) => { const q = v[(i + 1) % v.length]; return (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0]) > 0; });
    check(inside(col.com_x[k], col.com_y[k], overlay.vertices) === col.margin_static[k] > 0,
          "the CoM is inside the drawn polygon exactly when the run's static margin is positive", `margin ${col.margin_static[k]} m`);
    check(Number.isFinite(overlay.tip) && Math.abs(overlay.tip - col.margin_tip[k]) === 0, 'the tip-over margin shown is the run\'s', `${overlay.tip}`);
    const panelText = await api(dynamics, () => document.getElementById('forces-panel').innerText);
    check(!/NaN|undefined/.test(panelText) && /°/.test(panelText), 'the contacts panel shows finite margins', panelText.replace(/\s+/g, ' ').slice(0, 160));
    await api(dynamics, () => { document.getElementById('show-forces').click(); });
    check(!(await api(dynamics, () => wlxViewer.api.forces().shown)), 'the checkbox hides the overlay');
    const kinematic = await open('?run=NH-1');
    check((await api(kinematic, () => wlxViewer.api.forces())) === null, 'a kinematic run has no contacts overlay');
    // --- a run id with '+', encoded in the link as the report writes it; the scrub bar ------------
    const plus = await open('?run=' + encodeURIComponent('ST-A1+'));
    const plusRun = await api(plus, () => wlxViewer.api.runInfo());
    check(plusRun && plusRun.id === 'ST-A1+', 'viewer.html?run=ST-A1%2B opens run ST-A1+');
    await api(plus, () => { const s = document.getElementById('scrub'); s.value = '500'; s.dispatchEvent(new Event('input')); });
    const scrubbed = await api(plus, () => wlxViewer.api.time());
    check(Math.abs(scrubbed - (plusRun.start + plusRun.end) / 2) < 0.01 * (plusRun.end - plusRun.start) + 1e-9,
          'the scrub bar at its middle shows the run\'s middle', `t = ${scrubbed}`);
    // The centres of mass, when shown, are drawn without an error.
    await plus.click('#show-com');
    check((await api(plus, () => wlxViewer.api.message())) === '', 'showing the centres of mass');
    await plus.screenshot({ path: path.join(outDir, 'centres-of-mass.png') });

    // --- the second built-in model: its own tables, its own module ---------------------------------
    const walker = await open('?model=walker');
    const walkerPixels = await api(walker, () => wlxViewer.api.paintedPixels());
    check(walkerPixels.painted > 0.03 * walkerPixels.total, 'the walker renders', `${walkerPixels.painted} pixels`);
    const walkerHandles = await api(walker, () => wlxViewer.api.handles());
    const walkerCoordinates = Object.keys(await api(walker, () => wlxViewer.api.coordinates()));
    check(walkerCoordinates.includes('hub_l') && !walkerCoordinates.includes('psi_l2'), 'the walker page shows the walker\'s coordinates');
    const baseDrag = await api(walker, () => wlxViewer.api.drag('base-move', { z: -0.2 }, 5));
    check(baseDrag.ok && (await api(walker, () => wlxViewer.api.residual())) < 1e-9, 'dragging the walker\'s body keeps its closure',
          walkerHandles.map((h) => h.id).join(' '));
    await walker.screenshot({ path: path.join(outDir, 'walker.png') });

    // --- the third: a floating base on four wheeled legs (URDF), sixteen actuators --------------------
    const quadruped = await open('?model=wheeled_quadruped');
    const quadrupedPixels = await api(quadruped, () => wlxViewer.api.paintedPixels());
    check(quadrupedPixels.painted > 0.03 * quadrupedPixels.total, 'the wheeled quadruped renders', `${quadrupedPixels.painted} pixels`);
    const quadrupedCoordinates = Object.keys(await api(quadruped, () => wlxViewer.api.coordinates()));
    check(quadrupedCoordinates.includes('kfe_rh') && quadrupedCoordinates.includes('x_B'),
          'the wheeled quadruped\'s page shows its coordinates', quadrupedCoordinates.join(' '));
    // The page opens on the model's branches: its URDF's knees bend backwards only ([-2.8, -0.4] rad on
    // the left, [0.4, 2.8] about the mirrored axis on the right), as `wlx ik` solves them.
    const knees = await api(quadruped, () => wlxViewer.api.coordinates());
    check(knees.kfe_lf >= -2.8 && knees.kfe_lf <= -0.4 && knees.kfe_lh >= -2.8 && knees.kfe_lh <= -0.4 &&
          knees.kfe_rf >= 0.4 && knees.kfe_rf <= 2.8 && knees.kfe_rh >= 0.4 && knees.kfe_rh <= 2.8,
          'the wheeled quadruped opens with its knees within its joint limits',
          ['kfe_lf', 'kfe_rf', 'kfe_lh', 'kfe_rh'].map((k) => `${k} ${knees[k]}`).join(' '));
    const cliQuadruped = spawnSync(wlx, ['--model', 'wheeled_quadruped', 'ik'], { input: '{}', encoding: 'utf8' });
    const cliBranches = cliQuadruped.status === 0 ? JSON.parse(cliQuadruped.stdout).branch : null;
    const pageBranches = Object.fromEntries((await api(quadruped, () => wlxViewer.api.info())).limbs.map((l) => [l.name, l.defaultBranch]));
    check(cliBranches && JSON.stringify(pageBranches) === JSON.stringify(cliBranches),
          'the page\'s branches are the ones `wlx ik` takes with none given', `${JSON.stringify(pageBranches)} ${JSON.stringify(cliBranches)}`);
    const quadrupedBox = (await api(quadruped, () => wlxViewer.api.info())).clearanceBox;
    check(quadrupedBox && Math.abs(quadrupedBox.halfExtents[0] - 0.35) < 1e-9, 'the wheeled quadruped\'s base box is found',
          JSON.stringify(quadrupedBox));
    const quadrupedHandles = await api(quadruped, () => wlxViewer.api.handles());
    const lowered = await api(quadruped, () => wlxViewer.api.drag('base-move', { z: -0.1 }, 5));
    check(lowered.ok && (await api(quadruped, () => wlxViewer.api.residual())) < 1e-9,
          'lowering the wheeled quadruped\'s base keeps its four legs closed', quadrupedHandles.map((h) => h.id).join(' '));
    await quadruped.screenshot({ path: path.join(outDir, 'wheeled_quadruped.png') });
  } finally {
    await browser.close();
  }
  for (const e of errors) console.log(`FAIL ${e}`);
  failures += errors.length;
  console.log(failures ? `viewer_browser: ${failures} check(s) failed` : 'viewer_browser: all checks pass');
  process.exit(failures ? 1 : 0);
})().catch((e) => {
  console.error(`viewer_browser: ${e.stack || e}`);
  process.exit(1);
});
