/* medax 3D view: a minimal WebGL 1 viewer written for medax's HTML reports.
 *
 * Why not three.js: its current builds are ES modules split over two files (about 700 kB
 * minified) that do not inline into one self-contained file opened from file:// without
 * bundling, and the report needs little: shaded triangles, lines, an orbit camera and
 * picking. This file is about 300 lines and has no dependency.
 *
 * Data (see medax/cad/view_data.py): per model, base64 little-endian float32 positions
 * (n, 3), uint32 triangles (m, 3), float32 edge and axis segments (k, 2, 3), and per face
 * its index, solid, label, colour, surface, radius, neighbours and vertex / triangle ranges.
 *
 * Mouse: drag to orbit, wheel to zoom, right-drag or shift-drag to pan, click a face to see
 * what it is (picking: the faces drawn with their id as colour into an offscreen buffer).
 * After the first frame the viewer's element gets data-status="rendered" and data-rect (the
 * canvas's place in the page, CSS pixels: left, top, width, height; tests read them);
 * errors go into the page's #medax-errors element. The URL fragment can replay mouse input
 * after the first frame (#drag=DX,DY, #wheel=DY, #click=FX,FY; see replay); data-camera
 * holds yaw, pitch (rad) and distance after each frame, data-first-camera the first.
 */
(function () {
  'use strict';

  function bytes(s) {
    const b = atob(s), u = new Uint8Array(b.length);
    for (let i = 0; i < b.length; i++) u[i] = b.charCodeAt(i);
    return u.buffer;
  }
  const f32 = (s) => new Float32Array(bytes(s));
  const u32 = (s) => new Uint32Array(bytes(s));

  // ---- 4x4 matrices, column-major -------------------------------------------------------
  function mul(a, b) {
    const r = new Float32Array(16);
    for (let c = 0; c < 4; c++)
      for (let i = 0; i < 4; i++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + i] * b[c * 4 + k];
        r[c * 4 + i] = s;
      }
    return r;
  }
  function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), r = new Float32Array(16);
    r[0] = f / aspect; r[5] = f; r[10] = (far + near) / (near - far); r[11] = -1;
    r[14] = (2 * far * near) / (near - far);
    return r;
  }
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function unit(a) { const n = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / n, a[1] / n, a[2] / n]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function lookAt(eye, at, up) {
    const z = unit(sub(eye, at)), x = unit(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }

  // ---- shaders ----------------------------------------------------------------------------
  const FACE_VS = `
attribute vec3 aPos; attribute vec3 aNor; attribute vec3 aCol; attribute float aId;
uniform mat4 uMvp; uniform mat4 uView; uniform float uSel;
varying vec3 vCol; varying vec3 vNor; varying vec3 vPick;
void main() {
  gl_Position = uMvp * vec4(aPos, 1.0);
  vNor = (uView * vec4(aNor, 0.0)).xyz;
  vCol = abs(aId - uSel) < 0.5 ? mix(aCol, vec3(1.0, 0.92, 0.1), 0.65) : aCol;
  float id = aId + 1.0;
  vPick = vec3(mod(id, 256.0), mod(floor(id / 256.0), 256.0), floor(id / 65536.0)) / 255.0;
}`;
  const FACE_FS = `
precision mediump float;
uniform float uPick;
varying vec3 vCol; varying vec3 vNor; varying vec3 vPick;
void main() {
  if (uPick > 0.5) { gl_FragColor = vec4(vPick, 1.0); return; }
  vec3 n = normalize(vNor);
  float light = 0.35 + 0.65 * abs(dot(n, normalize(vec3(0.3, 0.5, 0.8))));
  gl_FragColor = vec4(vCol * light, 1.0);
}`;
  const LINE_VS = `
attribute vec3 aPos; uniform mat4 uMvp;
void main() { gl_Position = uMvp * vec4(aPos, 1.0); }`;
  const LINE_FS = `
precision mediump float; uniform vec3 uCol;
void main() { gl_FragColor = vec4(uCol, 1.0); }`;

  function program(gl, vs, fs) {
    const p = gl.createProgram();
    for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error('shader: ' + gl.getShaderInfoLog(s));
      gl.attachShader(p, s);
    }
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error('program: ' + gl.getProgramInfoLog(p));
    return p;
  }

  /** The arrays to draw one model: per triangle corner position, normal, colour, face id. */
  function expand(model) {
    const pos = f32(model.positions), idx = u32(model.indices), faces = model.faces;
    const nor = new Float32Array(pos.length);
    for (let t = 0; t < idx.length; t += 3) {  // smooth normals inside each face
      const a = idx[t] * 3, b = idx[t + 1] * 3, c = idx[t + 2] * 3;
      const n = cross([pos[b] - pos[a], pos[b + 1] - pos[a + 1], pos[b + 2] - pos[a + 2]],
        [pos[c] - pos[a], pos[c + 1] - pos[a + 1], pos[c + 2] - pos[a + 2]]);
      for (const v of [a, b, c]) { nor[v] += n[0]; nor[v + 1] += n[1]; nor[v + 2] += n[2]; }
    }
    const m = idx.length, P = new Float32Array(m * 3), N = new Float32Array(m * 3);
    const C = new Float32Array(m * 3), I = new Float32Array(m);
    faces.forEach((f, k) => {
      const [t0, nt] = f.triangles;
      for (let j = t0 * 3; j < (t0 + nt) * 3; j++) {
        const v = idx[j] * 3, n = unit([nor[v], nor[v + 1], nor[v + 2]]);
        for (let d = 0; d < 3; d++) { P[j * 3 + d] = pos[v + d]; N[j * 3 + d] = n[d]; C[j * 3 + d] = f.colour[d]; }
        I[j] = k;
      }
    });
    return { P, N, C, I, count: m, edges: f32(model.edges), axes: f32(model.axes) };
  }

  function View(root) {
    const canvas = root.querySelector('canvas'), info = root.querySelector('.mx-info');
    const legend = root.querySelector('.mx-legend'), select = root.querySelector('select');
    const gl = canvas.getContext('webgl', { antialias: true, preserveDrawingBuffer: true });
    if (!gl) throw new Error('WebGL is not available in this browser');
    const faceProg = program(gl, FACE_VS, FACE_FS), lineProg = program(gl, LINE_VS, LINE_FS);
    const buffers = {};
    for (const k of ['P', 'N', 'C', 'I', 'edges', 'axes']) buffers[k] = gl.createBuffer();
    const models = [...root.querySelectorAll('script.mx-model')];
    let model = null, arrays = null, selected = -1, drawn = false, queued = false;
    const cam = { yaw: -55 * Math.PI / 180, pitch: 28 * Math.PI / 180, dist: 1, centre: [0, 0, 0], radius: 1 };
    let mvp = null, view = null;

    function load(k) {
      model = JSON.parse(models[k].textContent);
      arrays = expand(model);
      for (const key of ['P', 'N', 'C', 'I', 'edges', 'axes']) {
        gl.bindBuffer(gl.ARRAY_BUFFER, buffers[key]);
        gl.bufferData(gl.ARRAY_BUFFER, arrays[key], gl.STATIC_DRAW);
      }
      const [lo, hi] = model.bounds;
      cam.centre = [0, 1, 2].map((d) => 0.5 * (lo[d] + hi[d]));
      cam.radius = Math.max(0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]), 1e-9);
      cam.dist = cam.radius / Math.sin(Math.PI * 35 / 360) * 1.05;
      selected = -1;
      info.textContent = 'click a face';
      legend.innerHTML = '';
      const items = model.legend.map((e) => [e.colour, `${e.label.replace('_', ' ')} (${e.count})`]);
      if (arrays.axes.length) items.push([[0.05, 0.05, 0.05], 'medial axis']);
      for (const [c, text] of items) {
        const s = document.createElement('span');
        s.innerHTML = `<i style="background:rgb(${c.map((v) => Math.round(v * 255))})"></i>`;
        s.appendChild(document.createTextNode(text));
        legend.appendChild(s);
      }
      request();
    }

    function matrices() {
      const w = canvas.width, h = canvas.height, c = cam.centre;
      const e = [c[0] + cam.dist * Math.cos(cam.pitch) * Math.cos(cam.yaw),
        c[1] + cam.dist * Math.cos(cam.pitch) * Math.sin(cam.yaw),
        c[2] + cam.dist * Math.sin(cam.pitch)];
      view = lookAt(e, c, [0, 0, 1]);
      const near = Math.max(cam.dist - 2 * cam.radius, cam.dist * 0.01), far = cam.dist + 2 * cam.radius;
      mvp = mul(perspective(Math.PI * 35 / 180, w / h, near, far), view);
    }

    function attrib(prog, name, key, size) {
      const loc = gl.getAttribLocation(prog, name);
      if (loc < 0) return;
      gl.bindBuffer(gl.ARRAY_BUFFER, buffers[key]);
      gl.enableVertexAttribArray(loc);
      gl.vertexAttribPointer(loc, size, gl.FLOAT, false, 0, 0);
    }

    function drawFaces(pick) {
      gl.useProgram(faceProg);
      gl.uniformMatrix4fv(gl.getUniformLocation(faceProg, 'uMvp'), false, mvp);
      gl.uniformMatrix4fv(gl.getUniformLocation(faceProg, 'uView'), false, view);
      gl.uniform1f(gl.getUniformLocation(faceProg, 'uSel'), selected);
      gl.uniform1f(gl.getUniformLocation(faceProg, 'uPick'), pick ? 1 : 0);
      attrib(faceProg, 'aPos', 'P', 3); attrib(faceProg, 'aNor', 'N', 3);
      attrib(faceProg, 'aCol', 'C', 3); attrib(faceProg, 'aId', 'I', 1);
      gl.enable(gl.POLYGON_OFFSET_FILL);
      gl.polygonOffset(1, 1);
      gl.drawArrays(gl.TRIANGLES, 0, arrays.count);
      gl.disable(gl.POLYGON_OFFSET_FILL);
      for (let i = 0; i < 4; i++) gl.disableVertexAttribArray(i);
    }

    function drawLines(key, rgb) {
      const n = arrays[key].length / 3;
      if (!n) return;
      gl.useProgram(lineProg);
      gl.uniformMatrix4fv(gl.getUniformLocation(lineProg, 'uMvp'), false, mvp);
      gl.uniform3fv(gl.getUniformLocation(lineProg, 'uCol'), rgb);
      attrib(lineProg, 'aPos', key, 3);
      gl.drawArrays(gl.LINES, 0, n);
      gl.disableVertexAttribArray(gl.getAttribLocation(lineProg, 'aPos'));
    }

    function resize() {
      const r = window.devicePixelRatio || 1;
      const w = Math.max(1, Math.round(canvas.clientWidth * r)), h = Math.max(1, Math.round(canvas.clientHeight * r));
      if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    }

    function draw() {
      queued = false;
      resize();
      matrices();
      gl.viewport(0, 0, canvas.width, canvas.height);
      gl.clearColor(1, 1, 1, 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      drawFaces(false);
      drawLines('edges', [0.12, 0.12, 0.12]);
      drawLines('axes', [0.05, 0.05, 0.05]);  // on the fillets: the faces are pushed back
      root.dataset.camera = [cam.yaw, cam.pitch, cam.dist].map((v) => v.toPrecision(6)).join(',');
      if (!drawn) {
        drawn = true;
        const b = canvas.getBoundingClientRect();
        root.dataset.rect = [b.left, b.top, b.width, b.height].map(Math.round).join(',');
        root.dataset.firstCamera = root.dataset.camera;
        replay(b);
        root.dataset.status = 'rendered';
        if (queued) draw();  // the replayed input's frame now, not at the next animation frame
      }
    }

    /** The mouse input the URL fragment names, sent through the same event handlers as a
     * user's: #drag=DX,DY (from the canvas's centre, pixels), #wheel=DY, #click=FX,FY
     * (fractions of the canvas); for tests and for links to a view. */
    function replay(b) {
      const h = location.hash, cx = b.left + b.width / 2, cy = b.top + b.height / 2;
      const mouse = (target, type, x, y) => target.dispatchEvent(
        new MouseEvent(type, { clientX: x, clientY: y, button: 0, bubbles: true }));
      const d = /drag=(-?[\d.]+),(-?[\d.]+)/.exec(h);
      if (d) {
        mouse(canvas, 'mousedown', cx, cy);
        mouse(window, 'mousemove', cx + parseFloat(d[1]), cy + parseFloat(d[2]));
        mouse(window, 'mouseup', cx + parseFloat(d[1]), cy + parseFloat(d[2]));
      }
      const w = /wheel=(-?[\d.]+)/.exec(h);
      if (w) canvas.dispatchEvent(new WheelEvent('wheel', { deltaY: parseFloat(w[1]), clientX: cx, clientY: cy, bubbles: true, cancelable: true }));
      const c = /click=([\d.]+),([\d.]+)/.exec(h);
      if (c) {
        const x = b.left + parseFloat(c[1]) * b.width, y = b.top + parseFloat(c[2]) * b.height;
        mouse(canvas, 'mousedown', x, y);
        mouse(canvas, 'mouseup', x, y);
      }
    }
    function request() { if (!queued) { queued = true; requestAnimationFrame(draw); } }

    /** The face under (x, y) CSS pixels of the canvas: drawn with ids into a framebuffer. */
    function pick(x, y) {
      resize();
      matrices();
      const w = canvas.width, h = canvas.height;
      const fb = gl.createFramebuffer(), tex = gl.createTexture(), depth = gl.createRenderbuffer();
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, w, h, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT16, w, h);
      gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
      gl.viewport(0, 0, w, h);
      gl.clearColor(0, 0, 0, 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      drawFaces(true);
      const px = new Uint8Array(4), r = w / canvas.clientWidth;
      gl.readPixels(Math.floor(x * r), Math.floor(h - 1 - y * r), 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.deleteFramebuffer(fb); gl.deleteTexture(tex); gl.deleteRenderbuffer(depth);
      selected = px[0] + 256 * px[1] + 65536 * px[2] - 1;
      show();
      request();
    }

    function show() {
      if (selected < 0 || selected >= model.faces.length) { info.textContent = 'no face there'; selected = -1; return; }
      const f = model.faces[selected];
      const solid = model.faces.some((g) => g.solid > 0) ? ` of solid ${f.solid}` : '';
      const radius = f.radius === undefined ? '' : `, radius ${+f.radius.toPrecision(6)}`;
      info.textContent = `face ${f.index}${solid}: ${f.label.replace('_', ' ')}, ${f.surface}${radius}; ` +
        `neighbours ${f.neighbours.join(', ') || 'none'} (${f.name})`;
      info.dataset.face = String(f.index);
      info.dataset.label = f.label;
    }

    // ---- mouse ----------------------------------------------------------------------------
    let drag = null;
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('mousedown', (e) => {
      drag = { x: e.clientX, y: e.clientY, x0: e.clientX, y0: e.clientY, pan: e.button === 2 || e.shiftKey };
    });
    window.addEventListener('mousemove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) {
        const s = 2 * cam.dist * Math.tan(Math.PI * 35 / 360) / canvas.clientHeight;
        const right = [view[0], view[4], view[8]], up = [view[1], view[5], view[9]];
        for (let d = 0; d < 3; d++) cam.centre[d] -= s * (dx * right[d] - dy * up[d]);
      } else {
        cam.yaw -= dx * 0.01;
        cam.pitch = Math.max(-1.55, Math.min(1.55, cam.pitch + dy * 0.01));
      }
      request();
    });
    window.addEventListener('mouseup', (e) => {
      if (drag && Math.hypot(e.clientX - drag.x0, e.clientY - drag.y0) < 4 && e.target === canvas) {
        const r = canvas.getBoundingClientRect();
        pick(e.clientX - r.left, e.clientY - r.top);
      }
      drag = null;
    });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      cam.dist = Math.max(cam.radius * 0.05, Math.min(cam.radius * 50, cam.dist * Math.exp(e.deltaY * 0.001)));
      request();
    }, { passive: false });
    window.addEventListener('resize', request);
    if (select) select.addEventListener('change', () => load(+select.value));
    root.medaxShow = (k) => { if (select) select.value = String(k); load(k); root.scrollIntoView(); };
    load(0);
    draw();  // the first frame now: a headless or busy browser may hold animation frames back
  }

  function record(text) {
    const box = document.getElementById('medax-errors');
    if (box) { box.hidden = false; box.appendChild(document.createTextNode(text + '\n')); }
  }
  for (const root of document.querySelectorAll('.mx-view')) {
    try { View(root); } catch (err) { root.dataset.status = 'error'; record(String(err && err.stack || err)); }
  }
})();
