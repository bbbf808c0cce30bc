// gradel in the browser: the page around the WebAssembly module (gradel.js + gradel.wasm, built
// from web/src/gradel_web.cpp). The module steps the simulation and builds the same draw list as
// gradel-view (surface with stress colour and legend, level wireframe, manipulators, walls);
// this file draws it with WebGL2, forwards the mouse, and shows the live figures.
// ?bench=1 runs the speed benchmark instead (rows of gradel-bench's CSV in #bench).
'use strict';

(function () {
  const $ = (id) => document.getElementById(id);
  const params = new URLSearchParams(location.search);
  const STEP_BUDGET_MS = 12;  // wall time per frame the simulation may use
  const FLOATS = 10;          // per vertex: position 3, normal 3, colour 4

  const status = (text, cls) => { const s = $('status'); s.textContent = text || ''; s.className = cls || ''; };

  createGradel().then((M) => (params.get('bench') ? runBench(M) : runDemo(M))).catch((e) => {
    status('could not start the WebAssembly module: ' + e);
    document.body.dataset.error = String(e);
  });

  // ---- benchmark mode: the paper's Table 1 setting, as gradel-bench measures it ----
  function runBench(M) {
    const sizes = (params.get('sizes') || '12,32').split(',').map(Number);
    const reps = Number(params.get('reps') || 5), minTime = Number(params.get('min_time') || 0.2);
    const out = $('bench');
    out.hidden = false;
    out.textContent = M.benchHeader() + '\n';
    status('benchmark running...');
    // Warm-up, not printed: V8 first runs wasm in its baseline compiler and tiers hot functions
    // up to the optimising one on background threads, which takes seconds on a busy machine.
    M.bench('sphere', sizes[0], 'gradational', 3, 0.5);
    let i = 0;
    const next = () => {
      if (i === sizes.length) {
        status('benchmark done');
        document.body.dataset.bench = 'done';
        return;
      }
      out.textContent += M.bench('sphere', sizes[i++], 'gradational', reps, minTime) + '\n';
      setTimeout(next, 10);
    };
    setTimeout(next, 10);
  }

  // ---- WebGL2 drawing of the draw list ----
  const VS = `#version 300 es
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec4 aColor;
uniform mat4 uMvp;
out vec3 vNormal;
out vec4 vColor;
void main() { gl_Position = uMvp * vec4(aPos, 1.0); vNormal = aNormal; vColor = aColor; }`;
  const FS = `#version 300 es
precision highp float;
in vec3 vNormal;
in vec4 vColor;
uniform int uLit;
uniform vec3 uLight;
out vec4 fragColor;
void main() {
  if (uLit == 0) { fragColor = vColor; return; }
  float d = abs(dot(normalize(vNormal), uLight));  // two-sided Lambert + ambient, as renderer.cpp
  fragColor = vec4(vColor.rgb * (0.35 + 0.65 * d), vColor.a);
}`;

  function makeRenderer(canvas) {
    const gl = canvas.getContext('webgl2', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) return null;
    const shader = (type, src) => {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    };
    const prog = gl.createProgram();
    gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS));
    gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
    const loc = { mvp: gl.getUniformLocation(prog, 'uMvp'), lit: gl.getUniformLocation(prog, 'uLit'), light: gl.getUniformLocation(prog, 'uLight') };
    const vao = gl.createVertexArray(), vbo = gl.createBuffer();
    gl.bindVertexArray(vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
    const stride = FLOATS * 4;
    for (const [i, n, off] of [[0, 3, 0], [1, 3, 12], [2, 4, 24]]) {
      gl.enableVertexAttribArray(i);
      gl.vertexAttribPointer(i, n, gl.FLOAT, false, stride, off);
    }
    const drawArray = (data, mode) => {
      if (!data.length) return;
      gl.bufferData(gl.ARRAY_BUFFER, data, gl.STREAM_DRAW);  // copies now: the view into wasm memory may move later
      gl.drawArrays(mode, 0, data.length / FLOATS);
    };
    return {
      gl,
      draw(demo, cssW, cssH) {
        const bg = demo.background();
        gl.viewport(0, 0, canvas.width, canvas.height);
        gl.clearColor(bg[0], bg[1], bg[2], 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        gl.useProgram(prog);
        gl.bindVertexArray(vao);
        gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
        gl.uniformMatrix4fv(loc.mvp, false, demo.viewProjection(cssW, cssH));
        gl.uniform3fv(loc.light, demo.light());
        gl.enable(gl.DEPTH_TEST);
        gl.depthFunc(gl.LEQUAL);
        gl.disable(gl.BLEND);
        gl.uniform1i(loc.lit, 1);
        gl.enable(gl.POLYGON_OFFSET_FILL);  // lines on the surface stay visible
        gl.polygonOffset(1, 1);
        drawArray(demo.triangles(), gl.TRIANGLES);
        gl.disable(gl.POLYGON_OFFSET_FILL);
        gl.uniform1i(loc.lit, 0);
        drawArray(demo.lines(), gl.LINES);
        // Overlay (legend, level key) in CSS pixels, y down.
        gl.disable(gl.DEPTH_TEST);
        gl.uniformMatrix4fv(loc.mvp, false, new Float32Array([2 / cssW, 0, 0, 0, 0, -2 / cssH, 0, 0, 0, 0, 1, 0, -1, 1, 0, 1]));
        drawArray(demo.overlay(), gl.TRIANGLES);
      },
    };
  }

  // ---- the demo ----
  function runDemo(M) {
    const canvas = $('view');
    const demo = new M.Demo();
    let renderer = null;
    try {
      renderer = makeRenderer(canvas);
    } catch (e) {
      status('WebGL2 error: ' + e.message);
    }
    if (!renderer) status('No WebGL2 in this browser: the simulation runs, but cannot be drawn.');

    let sceneName = 'play', paused = false, endTime = Infinity;
    const cache = {};
    const fetchScene = (name) => cache[name] ? Promise.resolve(cache[name])
      : fetch('scenes/' + name + '.json').then((r) => { if (!r.ok) throw new Error('scenes/' + name + '.json: HTTP ' + r.status); return r.text(); })
        .then((t) => (cache[name] = t));

    // A scene file, then the body chosen in the panel (the same physical size, so the
    // interactions still meet the ball).
    function loadScene(name) {
      return fetchScene(name).then((text) => {
        const err = demo.load(text, name + '.json');
        if (err) return status(err);
        sceneName = name;
        // The scene's end (simulation.duration, as gradel run): the play scene has none of its own.
        const duration = (JSON.parse(text).simulation || {}).duration;
        endTime = name === 'play' || !(duration > 0) ? Infinity : duration;
        $('end-out').textContent = Number.isFinite(endTime) ? endTime : '-';
        const body = bodyChoice();
        if (!(body.shape === 'sphere' && body.size === 12 && body.layout === 'gradational')) {
          const e = demo.setBody(body.shape, body.size, body.layout);
          if (e) status(e);
        }
        reframe();
        resetRates();
        status('');
      }).catch((e) => status(String(e)));
    }
    // Where the panel covers the left of the canvas (narrow windows), frame the scene right of it.
    const reframe = () => {
      const overlap = Math.max(0, $('panel').getBoundingClientRect().right - canvas.getBoundingClientRect().left);
      const [w, h] = size();
      demo.reframe(w > 2 * overlap ? overlap / 2 : 0, h);
    };
    const bodyChoice = () => ({ shape: $('shape').value, size: Number($('size').value), layout: $('layout').value });
    function applyBody() {
      const b = bodyChoice();
      $('size-out').textContent = b.size;
      const err = demo.setBody(b.shape, b.size, b.layout);
      status(err);
      resetRates();
    }
    function applyView() {
      // Stress scale 0: auto (the legend in Pa, 5 % strain of the stiffest material darkest).
      demo.setView(Number($('surface').value), $('stress').checked, $('wireframe').checked, 0);
    }

    for (const name of ['strike', 'grasp-wall', 'grasp-two', 'play'])
      $(name).addEventListener('click', () => loadScene(name));
    $('reset').addEventListener('click', () => loadScene(sceneName));
    $('pause').addEventListener('click', () => setPaused(!paused));
    $('reframe').addEventListener('click', () => reframe());
    $('follow').addEventListener('change', () => demo.setFollow($('follow').checked));
    demo.setFollow($('follow').checked);
    window.addEventListener('keydown', (e) => {
      if ((e.key === 'f' || e.key === 'F') && !(e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement)) reframe();
    });
    const setPaused = (p) => { paused = p; $('pause').textContent = paused ? 'Run' : 'Pause'; };
    $('size').addEventListener('input', () => { $('size-out').textContent = $('size').value; });
    for (const id of ['shape', 'size', 'layout']) $(id).addEventListener('change', applyBody);
    for (const id of ['stress', 'wireframe', 'surface']) $(id).addEventListener('change', applyView);
    applyView();

    // ---- mouse / touch (pointer events, CSS pixels) ----
    const size = () => [canvas.clientWidth, canvas.clientHeight];
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('pointerdown', (e) => {
      canvas.setPointerCapture(e.pointerId);
      const [w, h] = size();
      demo.pointerDown(e.offsetX, e.offsetY, e.button === 0 ? 0 : 1, w, h);
      canvas.style.cursor = demo.dragging() ? 'grabbing' : 'move';
    });
    canvas.addEventListener('pointermove', (e) => {
      const [w, h] = size();
      demo.pointerMove(e.offsetX, e.offsetY, e.shiftKey, w, h);
    });
    const up = () => { demo.pointerUp(); canvas.style.cursor = ''; };
    canvas.addEventListener('pointerup', up);
    canvas.addEventListener('pointercancel', up);
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      demo.wheel(-e.deltaY / 100, size()[1]);
    }, { passive: false });

    // ---- live figures over the last second ----
    let frames = [];  // [wall ms, steps, simulated s, behind]
    function resetRates() { frames = []; }
    function figures(now) {
      while (frames.length > 2 && now - frames[0][0] > 1000) frames.shift();
      let steps = 0, sim = 0, behind = false;
      for (let i = 1; i < frames.length; ++i) steps += frames[i][1], sim += frames[i][2], behind = behind || frames[i][3];
      const span = frames.length > 1 ? (frames[frames.length - 1][0] - frames[0][0]) / 1000 : 0;
      const c = demo.centreOfMass();
      $('fig-steps').textContent = span > 0 ? Math.round(steps / span) : 0;
      $('fig-rtf').textContent = span > 0 ? (sim / span).toFixed(2) : '0';
      $('fig-fps').textContent = span > 0 ? Math.round((frames.length - 1) / span) : 0;
      $('fig-elements').textContent = demo.elements();
      $('fig-vertices').textContent = demo.vertices();
      $('fig-time').textContent = demo.time().toFixed(3) + ' s / ' + (demo.dt() * 1e3).toFixed(3) + ' ms';
      $('fig-stress').textContent = demo.maxStressText();
      $('fig-com').textContent = Array.from(c, (v) => v.toFixed(4)).join(' ');
      if (behind && !paused) status('cannot keep up: the simulation runs slower than real time', 'behind');
      else if ($('status').className === 'behind') status('');
    }

    let last = performance.now(), lastFigures = 0;
    function frame(now) {
      const seconds = (now - last) / 1000;
      last = now;
      let steps = 0, sim = 0;
      if (!paused) {
        const t0 = demo.time();
        steps = demo.advance(seconds, STEP_BUDGET_MS, 1.0);
        sim = demo.time() - t0;
        if (demo.takeDiverged()) status('the simulation diverged and was restarted');
        if (t0 < endTime && demo.time() >= endTime) {  // crossed the scene's end
          const atEnd = $('at-end').value;
          if (atEnd === 'stop') setPaused(true), status("stopped at the scene's end (Run goes on)");
          if (atEnd === 'loop') loadScene(sceneName);
        }
      }
      frames.push([now, steps, sim, demo.behind()]);
      if (renderer) {
        const dpr = window.devicePixelRatio || 1, [w, h] = size();
        if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr))
          canvas.width = Math.round(w * dpr), canvas.height = Math.round(h * dpr);
        demo.buildFrame(w, h);
        renderer.draw(demo, w, h);
      }
      if (now - lastFigures > 250) {
        figures(now);
        lastFigures = now;
        document.body.dataset.ready = '1';
      }
      requestAnimationFrame(frame);
    }
    loadScene('play').then(() => requestAnimationFrame(frame));
    window.gradel = { demo, loadScene };  // for the console and the browser test
  }
})();
