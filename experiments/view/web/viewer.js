// The page of `ndcontour view` (docs/viewer.md): reads the mesh and summary.json that the tool
// embedded, projects R^d to 3-D with an orthogonal matrix R (three rows of R p are shown), draws
// with three.js, and publishes what it drew as window.ndcView for tests.
(function () {
  'use strict';
  const $ = (id) => document.getElementById(id);
  const SINGULAR = 0xe0201b, UNCERTIFIED = 0xff00d4;
  window.ndcView = { ready: false, triangles: 0, segments: 0, vertices: 0, n: 0 };

  function publish(extra) {
    Object.assign(window.ndcView, extra);
    $('ndc-view-state').textContent = JSON.stringify(window.ndcView);
  }

  /** The bytes of base64 text as a typed array of `Type`. */
  function decode(text, Type) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  // --- Data: coordinates centred and scaled together into [-1, 1]^d -----------------------
  const summary = JSON.parse($('ndc-summary').textContent);
  const data = JSON.parse($('ndc-mesh').textContent);
  const V = data.vertices, k = data.k, names = data.coordinates.slice();
  const first = names.length - data.n;  // of u0: 3 when x y z come first, else 0
  let raw = decode(data.positions, Float32Array);
  if (names.length < 3) {  // a curve in R^2: a third coordinate 0
    const wide = new Float32Array(V * 3);
    for (let v = 0; v < V; ++v) wide.set(raw.subarray(v * names.length, (v + 1) * names.length), v * 3);
    raw = wide;
    while (names.length < 3) names.push('0');
  }
  const d = names.length;
  const indices = decode(data.indices, Uint32Array);
  const uncertified = decode(data.uncertified, Uint8Array);
  const lo = new Array(d).fill(Infinity), hi = new Array(d).fill(-Infinity);
  for (let v = 0; v < V; ++v)
    for (let j = 0; j < d; ++j) {
      const x = raw[v * d + j];
      if (Number.isFinite(x)) { lo[j] = Math.min(lo[j], x); hi[j] = Math.max(hi[j], x); }
    }
  const centre = lo.map((l, j) => (Number.isFinite(l) ? (l + hi[j]) / 2 : 0));
  let scale = 1e-12;
  for (let j = 0; j < d; ++j) if (hi[j] > lo[j]) scale = Math.max(scale, (hi[j] - lo[j]) / 2);
  const unit = new Float64Array(V * d);
  for (let i = 0; i < V * d; ++i) unit[i] = (raw[i] - centre[i % d]) / scale;

  /** A point of R^n (a singular point) in the page's coordinates (x y z first when shown). */
  function pagePoint(point) {
    const p = new Float64Array(d);
    for (let j = 0; j < point.length && first + j < d; ++j)
      p[first + j] = (point[j] - centre[first + j]) / scale;
    return p;
  }
  const singular = ((summary.diagnostics || {}).singular_points || []).map((s) => pagePoint(s.point));
  const centres = decode(data.cells || '', Float32Array), n = data.n;
  const cells = Array.from({ length: centres.length / n }, (_, c) => pagePoint(centres.subarray(c * n, (c + 1) * n)));

  // --- The projection: R orthogonal (d x d); shown: rows axis[0..2] of R p -----------------
  const identity = () => Array.from({ length: d }, (_, i) => Float64Array.from({ length: d }, (_, j) => +(i === j)));
  let base = identity(), R = identity();
  const axis = [0, 1, 2];

  /** R = G(i, j, angle) B: a rotation by `angle` in the plane of coordinates i and j. */
  function rotated(B, i, j, angle) {
    const c = Math.cos(angle), s = Math.sin(angle), out = B.map((row) => Float64Array.from(row));
    for (let col = 0; col < d; ++col) {
      out[i][col] = c * B[i][col] - s * B[j][col];
      out[j][col] = s * B[i][col] + c * B[j][col];
    }
    return out;
  }

  function project(p, offset, out, at) {
    for (let m = 0; m < 3; ++m) {
      const row = R[axis[m]];
      let sum = 0;
      for (let j = 0; j < d; ++j) sum += row[j] * p[offset + j];
      out[at + m] = Number.isFinite(sum) ? sum : 0;
    }
  }

  // --- Colour maps ----------------------------------------------------------------------
  const MAPS = {
    viridis: [[0.267, 0.005, 0.329], [0.229, 0.322, 0.546], [0.128, 0.567, 0.551],
              [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]],
    coolwarm: [[0.230, 0.299, 0.754], [0.865, 0.865, 0.865], [0.706, 0.016, 0.150]],
    rainbow: [[0.25, 0.0, 0.8], [0.0, 0.4, 1.0], [0.0, 0.8, 0.4], [0.9, 0.85, 0.0], [0.95, 0.1, 0.0]],
  };
  function colourAt(map, t) {
    if (!Number.isFinite(t)) return [0.6, 0.6, 0.6];
    const stops = MAPS[map], x = Math.min(Math.max(t, 0), 1) * (stops.length - 1);
    const i = Math.min(Math.floor(x), stops.length - 2), f = x - i;
    return [0, 1, 2].map((c) => stops[i][c] * (1 - f) + stops[i + 1][c] * f);
  }

  // --- The scene ---------------------------------------------------------------------------
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    $('error').textContent = 'WebGL is not available: ' + e.message;
    publish({ error: 'no WebGL: ' + e.message });
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xf4f4f2);
  $('canvas').appendChild(renderer.domElement);
  const scene = new THREE.Scene(), group = new THREE.Group();
  scene.add(group);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  camera.position.set(0, 0, 6);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a80, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, 1.5, 2);
  camera.add(sun);
  scene.add(camera);
  group.rotation.set(-0.9, 0, -0.6);

  const positions = new THREE.BufferAttribute(new Float32Array(V * 3), 3);
  const colours = new THREE.BufferAttribute(new Float32Array(V * 3), 3);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', positions);
  geometry.setAttribute('color', colours);
  geometry.setIndex(new THREE.BufferAttribute(indices, 1));

  /** A geometry sharing the vertex positions, with the simplices of `list` (vertex indices). */
  function sharing(list) {
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', positions);
    g.setIndex(new THREE.BufferAttribute(Uint32Array.from(list), 1));
    return g;
  }
  const per = k + 1, simplices = indices.length / per;
  const bad = [];
  for (let s = 0; s < simplices; ++s)
    if (uncertified[s]) for (let m = 0; m < per; ++m) bad.push(indices[s * per + m]);

  let main, overlay, edges = null;
  if (k === 2) {
    main = new THREE.Mesh(geometry, new THREE.MeshPhongMaterial({
      vertexColors: true, side: THREE.DoubleSide, shininess: 25,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 }));
    overlay = new THREE.Mesh(sharing(bad), new THREE.MeshBasicMaterial({
      color: UNCERTIFIED, side: THREE.DoubleSide }));
    const seen = new Set(), list = [];
    for (let s = 0; s < simplices; ++s)
      for (let m = 0; m < 3; ++m) {
        const a = indices[s * 3 + m], b = indices[s * 3 + (m + 1) % 3];
        const key = Math.min(a, b) * V + Math.max(a, b);
        if (!seen.has(key)) { seen.add(key); list.push(a, b); }
      }
    edges = new THREE.LineSegments(sharing(list), new THREE.LineBasicMaterial({
      color: 0x202020, transparent: true, opacity: 0.35 }));
    edges.visible = false;
    group.add(edges);
  } else {
    main = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
    // WebGL lines are one pixel wide: the vertices as dots make a curve easier to see.
    group.add(new THREE.Points(geometry, new THREE.PointsMaterial({
      vertexColors: true, size: 4, sizeAttenuation: false })));
    overlay = new THREE.LineSegments(sharing(bad), new THREE.LineBasicMaterial({ color: UNCERTIFIED }));
  }
  overlay.renderOrder = 1;
  group.add(main, overlay);
  // The uncertified cells: a small cube at the centre of each (one instanced mesh).
  const cellMarks = new THREE.InstancedMesh(new THREE.BoxGeometry(0.022, 0.022, 0.022),
    new THREE.MeshBasicMaterial({ color: UNCERTIFIED }), Math.max(cells.length, 1));
  cellMarks.count = cells.length;
  cellMarks.renderOrder = 2;
  group.add(cellMarks);
  const markers = singular.map(() => {
    const m = new THREE.Mesh(new THREE.SphereGeometry(0.035, 20, 14),
                             new THREE.MeshPhongMaterial({ color: SINGULAR }));
    m.renderOrder = 2;
    group.add(m);
    return m;
  });

  // --- Updates -----------------------------------------------------------------------------
  let dirty = true;
  function updatePositions() {
    const a = positions.array;
    for (let v = 0; v < V; ++v) project(unit, v * d, a, v * 3);
    positions.needsUpdate = true;
    if (k === 2) geometry.computeVertexNormals();
    geometry.computeBoundingSphere();
    const q = new Float64Array(3);
    singular.forEach((p, i) => { project(p, 0, q, 0); markers[i].position.set(q[0], q[1], q[2]); });
    const place = new THREE.Matrix4();
    cells.forEach((p, i) => { project(p, 0, q, 0); cellMarks.setMatrixAt(i, place.makeTranslation(q[0], q[1], q[2])); });
    cellMarks.instanceMatrix.needsUpdate = true;
    dirty = true;
  }

  function updateColours() {
    const c = +$('colorBy').value, map = $('colormap').value, a = colours.array;
    const span = hi[c] > lo[c] ? hi[c] - lo[c] : 1;
    for (let v = 0; v < V; ++v) a.set(colourAt(map, (raw[v * d + c] - lo[c]) / span), v * 3);
    colours.needsUpdate = true;
    const bar = $('colorbar').getContext('2d');
    for (let x = 0; x < 220; ++x) {
      const [r, g, b] = colourAt(map, x / 219);
      bar.fillStyle = `rgb(${255 * r | 0},${255 * g | 0},${255 * b | 0})`;
      bar.fillRect(x, 0, 1, 12);
    }
    $('colorName').textContent = 'colour: ' + names[c];
    $('colorMin').textContent = Number.isFinite(lo[c]) ? lo[c].toPrecision(3) : '';
    $('colorMax').textContent = Number.isFinite(hi[c]) ? hi[c].toPrecision(3) : '';
    dirty = true;
  }

  function updateVisibility() {
    markers.forEach((m) => { m.visible = $('showSingular').checked; });
    overlay.visible = cellMarks.visible = $('showUncertified').checked;
    if (edges) edges.visible = $('showWire').checked;
    dirty = true;
  }

  // --- Controls ----------------------------------------------------------------------------
  function fillSelect(id, value) {
    const s = $(id);
    names.forEach((name, j) => s.add(new Option(name, j)));
    s.value = value;
  }
  axis.forEach((a, m) => fillSelect('axis' + m, a));
  // Beyond R^3 the first view turns each shown axis m by 30 degrees towards coordinate m + 3
  // (where there is one), so that sheets that the plain projection to three coordinates lays
  // on top of each other (a double cover) come apart. `Reset` shows the plain coordinates.
  fillSelect('planeI', 0);
  fillSelect('planeJ', Math.min(3, d - 1));
  for (let m = 0; m < 3 && m + 3 < d; ++m) base = rotated(base, m, m + 3, Math.PI / 6);
  R = base;
  fillSelect('colorBy', first + Math.min(3, data.n - 1));  // u3, or the last of u0 .. u{n-1}

  const plane = () => [+$('planeI').value, +$('planeJ').value];
  function commitRotation() { base = R; $('angle').value = 0; $('angleText').textContent = '0°'; }
  [0, 1, 2].forEach((m) => $('axis' + m).addEventListener('change', () => {
    axis[m] = +$('axis' + m).value;
    updatePositions();
  }));
  ['planeI', 'planeJ'].forEach((id) => $(id).addEventListener('change', commitRotation));
  $('angle').addEventListener('input', () => {
    const [i, j] = plane(), deg = +$('angle').value;
    $('angleText').textContent = deg + '°';
    R = i === j ? base : rotated(base, i, j, (deg * Math.PI) / 180);
    updatePositions();
  });
  $('reset').addEventListener('click', () => { R = identity(); commitRotation(); updatePositions(); });
  $('colorBy').addEventListener('change', updateColours);
  $('colormap').addEventListener('change', updateColours);
  ['showSingular', 'showUncertified', 'showWire'].forEach((id) =>
    $(id).addEventListener('change', updateVisibility));

  // Mouse: drag turns the 3-D view, the wheel zooms.
  let drag = null;
  renderer.domElement.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; });
  window.addEventListener('pointerup', () => { drag = null; });
  window.addEventListener('pointermove', (e) => {
    if (!drag) return;
    const dx = (e.clientX - drag[0]) * 0.01, dy = (e.clientY - drag[1]) * 0.01;
    drag = [e.clientX, e.clientY];
    const q = new THREE.Quaternion().setFromEuler(new THREE.Euler(dy, dx, 0));
    group.quaternion.premultiply(q);
    dirty = true;
  });
  renderer.domElement.addEventListener('wheel', (e) => {
    e.preventDefault();
    camera.position.z = Math.min(Math.max(camera.position.z * Math.exp(e.deltaY * 0.001), 1), 40);
    dirty = true;
  }, { passive: false });

  // The grand tour: small rotations in a plane of R^d drawn at random, a new one every 2.5 s.
  let tourPlane = [0, Math.min(3, d - 1)], tourSince = 0;
  function tourStep(time) {
    if (time - tourSince > 2500 || tourPlane[0] === tourPlane[1]) {
      const i = Math.floor(Math.random() * d);
      tourPlane = [i, (i + 1 + Math.floor(Math.random() * (d - 1))) % d];
      tourSince = time;
    }
    R = rotated(R, tourPlane[0], tourPlane[1], 0.01);
    base = R;
    updatePositions();
  }

  function resize() {
    renderer.setSize(window.innerWidth, window.innerHeight);
    camera.aspect = window.innerWidth / Math.max(window.innerHeight, 1);
    camera.updateProjectionMatrix();
    dirty = true;
  }
  window.addEventListener('resize', resize);

  // --- Text --------------------------------------------------------------------------------
  const mesh = summary.mesh || {}, topology = summary.topology || {};
  const count = simplices;
  const bads = uncertified.reduce((a, b) => a + b, 0);
  $('title').textContent = (summary.problem || data.source) + ' (n = ' + data.n + ', k = ' + k + ')';
  $('dim').textContent = d;
  const rows = [
    ['vertices', V], [k === 2 ? 'triangles' : 'segments', count],
    ['components', mesh.components], ['Euler characteristic', mesh.euler_characteristic],
    ['topology', topology.certified === undefined ? '?' :
      topology.certified ? 'certified' : 'not certified' + (topology.reason ? ': ' + topology.reason : '')],
    ['singular points', singular.length], ['uncertified cells', cells.length],
    ['uncertified simplices', bads]];
  $('info').innerHTML = rows.filter((r) => r[1] !== undefined)
    .map((r) => `<div><b>${r[0]}</b>: ${String(r[1]).replace(/</g, '&lt;')}</div>`).join('');
  $('singularText').textContent = 'singular point (' + singular.length + ')';
  $('uncertifiedText').textContent = 'uncertified cell (' + cells.length + ': cubes at the centres; ' +
    bads + (k === 2 ? ' triangles' : ' segments') + ' inside)';

  // --- Go ----------------------------------------------------------------------------------
  resize();
  updatePositions();
  updateColours();
  updateVisibility();
  let firstFrame = true;
  function frame(time) {
    if ($('tour').checked) tourStep(time);
    if (dirty) {
      renderer.render(scene, camera);
      dirty = false;
      if (firstFrame) {
        firstFrame = false;
        publish({ ready: true, n: data.n, k: k, vertices: V, dimensions: d,
                  triangles: k === 2 ? main.geometry.index.count / 3 : 0,
                  segments: k === 1 ? main.geometry.index.count / 2 : 0,
                  uncertified: overlay.geometry.index.count / per, singular: markers.length,
                  uncertifiedCells: cellMarks.count });
      }
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
