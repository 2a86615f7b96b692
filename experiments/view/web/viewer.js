// The page of `ndcontour view` (docs/viewer.md): reads the mesh and summary.json that the tool
// embedded, projects R^d to 3-D with an orthogonal matrix R (three rows of R p are shown), draws
// with three.js and an axis triad of R^d, and publishes what it drew as window.ndcView for tests.
// A k-manifold for k >= 3 is drawn as a slice (its k-simplices cut by a hyperplane u_j = t) or
// as its skeleton (every edge).
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
  // The problem's variable names (summary.json `variables`) for u0 .. u{n-1}, where given.
  const variables = summary.variables;
  if (Array.isArray(variables) && variables.length === data.n &&
      variables.every((v) => typeof v === 'string' && v.length > 0)) {
    variables.forEach((v, j) => { names[first + j] = v; });
    // An application's 3-D image x y z beside variables of the same names: say which is which.
    if (first === 3 && variables.some((v) => ['x', 'y', 'z'].includes(v)))
      for (let m = 0; m < 3; ++m) names[m] += ' (image)';
  }
  const axes = names.length;  // the coordinate axes of the page's R^d (before any padding)
  const emptyZeroSet = !!(summary.diagnostics || {}).empty_zero_set;
  // Settings in the page's address after '#', e.g. view.html#colour=component&map=rainbow.
  const params = new Map(location.hash.slice(1).split('&').filter(Boolean).map((p) => {
    const at = p.indexOf('=');
    return at < 0 ? [decodeURIComponent(p), ''] : [decodeURIComponent(p.slice(0, at)), decodeURIComponent(p.slice(at + 1))];
  }));
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

  // --- Connected components: union-find over the simplices' vertices (an isolated vertex is a
  // component of its own, as mesh.components of summary.json counts them) ------------------
  const parent = Int32Array.from({ length: V }, (_, v) => v);
  function root(v) {
    while (parent[v] !== v) { parent[v] = parent[parent[v]]; v = parent[v]; }
    return v;
  }
  for (let s = 0; s < indices.length; s += k + 1)
    for (let m = 1; m <= k; ++m) {
      const a = root(indices[s]), b = root(indices[s + m]);
      if (a !== b) parent[Math.max(a, b)] = Math.min(a, b);
    }
  const component = new Int32Array(V);  // numbered 0, 1, .. in the order of their first vertex
  let components = 0;
  {
    const number = new Int32Array(V).fill(-1);
    for (let v = 0; v < V; ++v) {
      const r = root(v);
      if (number[r] < 0) number[r] = components++;
      component[v] = number[r];
    }
  }
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
  // Components: tab10 without its red and pink (the singular points and uncertified cells' colours).
  const CATEGORIES = [[0.122, 0.467, 0.706], [1.0, 0.498, 0.055], [0.173, 0.627, 0.173],
                      [0.580, 0.404, 0.741], [0.549, 0.337, 0.294], [0.737, 0.741, 0.133],
                      [0.090, 0.745, 0.812], [0.498, 0.498, 0.498]];
  const PLAIN = [0.27, 0.45, 0.70];
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
  renderer.autoClear = false;  // draw() clears once, then draws the mesh and the triad
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

  /** The distinct edges of the simplices (of those flagged in `which` when given), as pairs. */
  function edgeList(which) {
    const seen = new Set(), list = [];
    for (let s = 0; s < simplices; ++s) {
      if (which && !which[s]) continue;
      for (let m = 0; m < per; ++m)
        for (let l = m + 1; l < per; ++l) {
          const a = indices[s * per + m], b = indices[s * per + l];
          const key = Math.min(a, b) * V + Math.max(a, b);
          if (!seen.has(key)) { seen.add(key); list.push(a, b); }
        }
    }
    return list;
  }

  let main, overlay, edges = null, skeleton = null;
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
  } else if (k === 1) {
    main = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
    // WebGL lines are one pixel wide: the vertices as dots make a curve easier to see.
    group.add(new THREE.Points(geometry, new THREE.PointsMaterial({
      vertexColors: true, size: 4, sizeAttenuation: false })));
    overlay = new THREE.LineSegments(sharing(bad), new THREE.LineBasicMaterial({ color: UNCERTIFIED }));
  } else {
    // k >= 3: the slice (main: triangles for k = 3, the edges of the cut pieces beyond; its
    // geometry is made by updateSlice) and the skeleton, in the vertices' colours; the edges of
    // the uncertified simplices in magenta.
    main = k === 3
      ? new THREE.Mesh(new THREE.BufferGeometry(), new THREE.MeshPhongMaterial({
        vertexColors: true, side: THREE.DoubleSide, shininess: 25 }))
      : new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ vertexColors: true }));
    main.frustumCulled = false;
    const all = sharing(edgeList(null));
    all.setAttribute('color', colours);
    skeleton = new THREE.LineSegments(all, new THREE.LineBasicMaterial({
      vertexColors: true, transparent: true, opacity: 0.6 }));
    group.add(skeleton);
    overlay = new THREE.LineSegments(sharing(edgeList(uncertified)), new THREE.LineBasicMaterial({ color: UNCERTIFIED }));
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

  // --- The axis triad: where each coordinate axis e_j of R^d goes, drawn in a corner -------
  // The arrow of axis j is (R_a0 j, R_a1 j, R_a2 j) (column j of the shown rows of R), turned
  // like the mesh by the mouse; its length is 1 when e_j lies in the shown 3-space, 0 when the
  // projection drops it. The circle is length 1.
  const TRIAD = 150;  // CSS pixels, lower right
  const triadScene = new THREE.Scene(), triadGroup = new THREE.Group();
  triadScene.add(triadGroup);
  const triadCamera = new THREE.OrthographicCamera(-1.55, 1.55, 1.55, -1.55, -10, 10);
  {
    const ring = [];
    for (let a = 0; a <= 64; ++a) ring.push(new THREE.Vector3(Math.cos(a * Math.PI / 32), Math.sin(a * Math.PI / 32), 0));
    triadScene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(ring),
      new THREE.LineBasicMaterial({ color: 0xb0b0b0 })));
  }
  const triad = Array.from({ length: axes }, (_, j) => {
    const colour = new THREE.Color().setHSL(j / axes * 0.85, 0.8, 0.34);
    const line = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
      new THREE.LineBasicMaterial({ color: colour, depthTest: false }));
    const tip = new THREE.Mesh(new THREE.SphereGeometry(0.045, 10, 8),
      new THREE.MeshBasicMaterial({ color: colour, depthTest: false }));
    // The label: the coordinate's name drawn into a texture, on a sprite beyond the tip.
    const text = document.createElement('canvas'), font = 'bold 32px system-ui, sans-serif';
    let g = text.getContext('2d');
    g.font = font;
    text.width = Math.ceil(g.measureText(names[j]).width) + 12;
    text.height = 44;
    g = text.getContext('2d');
    g.font = font;
    g.textBaseline = 'middle';
    g.lineWidth = 6;
    g.strokeStyle = 'rgba(244, 244, 242, 0.9)';
    g.strokeText(names[j], 6, 23);
    g.fillStyle = '#' + colour.getHexString();
    g.fillText(names[j], 6, 23);
    const texture = new THREE.CanvasTexture(text);
    texture.colorSpace = THREE.SRGBColorSpace;
    const label = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, depthTest: false }));
    label.scale.set(0.42 * text.width / text.height, 0.42, 1);
    label.renderOrder = 3;
    triadGroup.add(line, tip);
    triadScene.add(label);  // placed on the screen by updateTriad
    return { line, tip, label, vector: new THREE.Vector3() };
  });

  function updateTriad() {
    triadGroup.quaternion.copy(group.quaternion);
    const central = [];
    triad.forEach((t, j) => {
      t.vector.set(R[axis[0]][j], R[axis[1]][j], R[axis[2]][j]);
      const ends = t.line.geometry.attributes.position;
      ends.setXYZ(1, t.vector.x, t.vector.y, t.vector.z);
      ends.needsUpdate = true;
      t.tip.position.copy(t.vector);
      // The label beyond the tip as seen on the screen; the labels of arrows too short to see
      // (axes that the projection drops, or that point at the viewer) in a column at the centre.
      const seen = t.vector.clone().applyQuaternion(group.quaternion), length = Math.hypot(seen.x, seen.y);
      if (length < 0.15) central.push(t);
      else t.label.position.set(seen.x * (length + 0.3) / length, seen.y * (length + 0.3) / length, 1);
    });
    central.forEach((t, i) => t.label.position.set(0, ((central.length - 1) / 2 - i) * 0.42, 1));
  }

  /** The arrows as the page shows them: in the camera's frame (x right, y up, z to the viewer). */
  function triadState() {
    return triad.map((t, j) => {
      const v = t.vector.clone().applyQuaternion(group.quaternion);
      return { label: names[j], x: v.x, y: v.y, z: v.z };
    });
  }

  // --- k >= 3: the slice by the hyperplane u_j = t -----------------------------------------
  // Each k-simplex with vertices on both sides (u_j - t > 0 or not) is cut in a (k-1)-piece. For
  // k = 3 it is a triangle (one vertex apart) or a quad (two and two), drawn as two triangles;
  // beyond, the piece's edges: where the hyperplane cuts a triangle of the simplex. A point of the
  // slice lies on a mesh edge (a, b) at the fraction f from a, so its position and its colour
  // follow a and b (the projection is linear): sliceEnds holds a, b, f per point, sliceBad
  // whether its simplex is uncertified (drawn in magenta, as the simplices of k = 2).
  let sliceEnds = new Float64Array(0), sliceBad = new Uint8Array(0), slicePoints = 0, sliceCut = 0;
  const sliceAxis = () => +$('sliceAxis').value;  // a coordinate of the page
  function sliceValue() {
    const c = sliceAxis();
    if (!(hi[c] >= lo[c])) return 0;
    return lo[c] + (hi[c] - lo[c]) * +$('slice').value / 1000;
  }

  /** The points of the slice u_c = t, three per triangle (k = 3) or two per segment; `bad`
   * gets the uncertified flag of each point's simplex. */
  function cutSimplices(c, t, bad) {
    const out = [], value = new Float64Array(per);
    let s = 0;
    const point = (m, l) => {
      out.push(indices[s * per + m], indices[s * per + l], value[m] / (value[m] - value[l]));
      bad.push(uncertified[s]);
    };
    const above = (m) => value[m] > 0;
    sliceCut = 0;
    for (; s < simplices; ++s) {
      let up = 0;
      for (let m = 0; m < per; ++m) { value[m] = raw[indices[s * per + m] * d + c] - t; up += above(m); }
      if (up === 0 || up === per) continue;
      ++sliceCut;
      if (k === 3) {
        const ups = [0, 1, 2, 3].filter(above), downs = [0, 1, 2, 3].filter((m) => !above(m));
        if (ups.length === 2) {  // the quad pu pv qv qu, as two triangles
          const [p, q] = ups, [u, v] = downs;
          point(p, u); point(p, v); point(q, v);
          point(p, u); point(q, v); point(q, u);
        } else {  // a triangle: the three edges at the vertex apart
          const [lone, rest] = ups.length === 1 ? [ups[0], downs] : [downs[0], ups];
          rest.forEach((m) => point(lone, m));
        }
        continue;
      }
      for (let m = 0; m < per; ++m)  // k >= 4: a segment per triangle m < l < o that is cut
        for (let l = m + 1; l < per; ++l)
          for (let o = l + 1; o < per; ++o) {
            const cut = [[m, l], [l, o], [m, o]].filter(([x, y]) => above(x) !== above(y));
            if (cut.length === 2) cut.forEach(([x, y]) => point(x, y));
          }
    }
    return out;
  }

  /** The slice's points where the vertices are drawn now (lerp of their projections). */
  function placeSlice() {
    const at = main.geometry.getAttribute('position');
    if (!at) return;
    const a = positions.array, out = at.array;
    for (let i = 0; i < slicePoints; ++i) {
      const v = sliceEnds[3 * i], w = sliceEnds[3 * i + 1], f = sliceEnds[3 * i + 2];
      for (let m = 0; m < 3; ++m) out[3 * i + m] = (1 - f) * a[3 * v + m] + f * a[3 * w + m];
    }
    at.needsUpdate = true;
    if (k === 3) main.geometry.computeVertexNormals();
  }

  /** Cuts the simplices anew at the slider's hyperplane. */
  function updateSlice() {
    const c = sliceAxis(), t = sliceValue();
    const bad = [];
    sliceEnds = Float64Array.from(cutSimplices(c, t, bad));
    sliceBad = Uint8Array.from(bad);
    slicePoints = sliceEnds.length / 3;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(slicePoints * 3), 3));
    g.setAttribute('color', new THREE.BufferAttribute(new Float32Array(slicePoints * 3), 3));
    main.geometry.dispose();
    main.geometry = g;
    $('sliceText').textContent = Number.isFinite(t) ? t.toPrecision(3) : '';
    placeSlice();
    colourSlice();
    dirty = true;
  }

  /** What is drawn as triangles and as segments, and how. */
  function drawn() {
    const slice = k >= 3 && $('mode').value === 'slice';
    const shown = { triangles: k === 2 ? main.geometry.index.count / 3 : k === 3 && slice ? slicePoints / 3 : 0,
                    segments: k === 1 ? main.geometry.index.count / 2 : k < 3 ? 0
                      : slice ? (k > 3 ? slicePoints / 2 : 0) : skeleton.geometry.index.count / 2 };
    if (k >= 3)
      Object.assign(shown, { mode: $('mode').value, skeletonEdges: skeleton.geometry.index.count / 2,
        slice: { axis: names[sliceAxis()], value: sliceValue(), simplices: sliceCut } });
    return shown;
  }

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
    if (k >= 3) placeSlice();
    updateTriad();
    dirty = true;
  }

  /** What the colour select says: 'component', 'plain' or the name of a coordinate. */
  function colourMode() {
    const value = $('colorBy').value;
    return value === 'component' || value === 'plain' ? value : names[+value];
  }

  function updateColours() {
    const mode = $('colorBy').value, map = $('colormap').value, a = colours.array;
    // The colour bar: a coordinate's map, one swatch per component (cycling), or one colour.
    let barColour, name, min = '', max = '';
    if (mode === 'component') {
      for (let v = 0; v < V; ++v) a.set(CATEGORIES[component[v] % CATEGORIES.length], v * 3);
      const swatches = Math.max(Math.min(components, 16), 1);
      barColour = (t) => CATEGORIES[Math.min(Math.floor(t * swatches), swatches - 1) % CATEGORIES.length];
      name = 'colour: connected component (' + components + ')';
      if (components > 0) { min = '1'; max = String(components); }
    } else if (mode === 'plain') {
      for (let v = 0; v < V; ++v) a.set(PLAIN, v * 3);
      barColour = () => PLAIN;
      name = 'colour: plain';
    } else {
      const c = +mode, span = hi[c] > lo[c] ? hi[c] - lo[c] : 1;
      for (let v = 0; v < V; ++v) a.set(colourAt(map, (raw[v * d + c] - lo[c]) / span), v * 3);
      barColour = (t) => colourAt(map, t);
      name = 'colour: ' + names[c];
      if (Number.isFinite(lo[c])) { min = lo[c].toPrecision(3); max = hi[c].toPrecision(3); }
    }
    // The maps are sRGB; three.js takes vertex colours as linear and converts them on output.
    linear(a);
    colours.needsUpdate = true;
    if (k >= 3) colourSlice();
    $('colormap').disabled = mode === 'component' || mode === 'plain';
    const bar = $('colorbar').getContext('2d');
    for (let x = 0; x < 220; ++x) {
      const [r, g, b] = barColour(x / 219);
      bar.fillStyle = `rgb(${255 * r | 0},${255 * g | 0},${255 * b | 0})`;
      bar.fillRect(x, 0, 1, 12);
    }
    $('colorName').textContent = name;
    $('colorMin').textContent = min;
    $('colorMax').textContent = max;
    dirty = true;
  }

  /** sRGB colours (0 .. 1) made linear, in place. */
  function linear(a) {
    for (let i = 0; i < a.length; ++i) a[i] = a[i] <= 0.04045 ? a[i] / 12.92 : Math.pow((a[i] + 0.055) / 1.055, 2.4);
  }

  /** The slice's colours: a coordinate's value where the point lies, or its edge's component. */
  function colourSlice() {
    const at = main.geometry.getAttribute('color');
    if (!at) return;
    const mode = $('colorBy').value, map = $('colormap').value, out = at.array;
    const c = +mode, span = hi[c] > lo[c] ? hi[c] - lo[c] : 1, magenta = $('showUncertified').checked;
    for (let i = 0; i < slicePoints; ++i) {
      const v = sliceEnds[3 * i], w = sliceEnds[3 * i + 1], f = sliceEnds[3 * i + 2];
      out.set(magenta && sliceBad[i] ? [1, 0, 0.831] : mode === 'component' ? CATEGORIES[component[v] % CATEGORIES.length] : mode === 'plain' ? PLAIN
        : colourAt(map, ((1 - f) * raw[v * d + c] + f * raw[w * d + c] - lo[c]) / span), 3 * i);
    }
    linear(out);
    at.needsUpdate = true;
    dirty = true;
  }

  function updateVisibility() {
    markers.forEach((m) => { m.visible = $('showSingular').checked; });
    overlay.visible = cellMarks.visible = $('showUncertified').checked;
    if (edges) edges.visible = $('showWire').checked;
    if (skeleton) {  // k >= 3: the uncertified simplices as edges in the skeleton, in the slice's colours
      main.visible = $('mode').value === 'slice';
      skeleton.visible = !main.visible;
      overlay.visible = overlay.visible && skeleton.visible;
      colourSlice();
      showCounts();
    }
    triadScene.visible = $('showTriad').checked;
    dirty = true;
  }

  // --- Controls ----------------------------------------------------------------------------
  function fillSelect(id, value) {
    const s = $(id);
    names.forEach((name, j) => s.add(new Option(name, j)));
    s.value = value;
  }
  axis.forEach((a, m) => fillSelect('axis' + m, a));
  // Beyond R^3 the first view is turned by 30 degrees in the plane of the first and the fourth
  // coordinate, so that sheets that the plain projection to three coordinates lays on top of
  // each other (a double cover, the Clifford torus) come apart. The controls say so (plane
  // u0 - u3, slider at 30) and R is made from them as by the slider: what they read is what is
  // drawn. `Reset` shows the plain coordinates.
  fillSelect('planeI', 0);
  fillSelect('planeJ', Math.min(3, d - 1));
  $('angle').value = d > 3 && k < 3 ? 30 : 0;  // k >= 3: the slice shows the plain coordinates
  // k >= 3: the slice (the default) or the skeleton, #mode= in the address; the hyperplane
  // u_j = t, j the last coordinate (#slice=NAME) and t the middle of its range (#at=VALUE).
  if (k >= 3) {
    $('higher').hidden = false;
    $('showWire').disabled = true;  // the skeleton is the mode below
    $('kText').textContent = k;
    names.forEach((name, j) => { if (j < axes) $('sliceAxis').add(new Option(name, j)); });
    const wanted = params.get('slice') || '', byName = names.indexOf(wanted);
    const byU = /^u\d+$/.test(wanted) ? first + +wanted.slice(1) : -1;
    $('sliceAxis').value = byName >= 0 && byName < axes ? byName : byU >= first && byU < axes ? byU : axes - 1;
    $('mode').value = params.get('mode') === 'skeleton' ? 'skeleton' : 'slice';
    const at = parseFloat(params.get('at')), c = sliceAxis();
    if (Number.isFinite(at) && hi[c] > lo[c]) $('slice').value = Math.round((at - lo[c]) / (hi[c] - lo[c]) * 1000);
    $('mode').addEventListener('change', updateVisibility);
    $('sliceAxis').addEventListener('change', () => { $('slice').value = 500; updateSlice(); showCounts(); });
    $('slice').addEventListener('input', () => { updateSlice(); showCounts(); });
  }
  // The colour: #colour= in the address, else by component when there are several, else u3
  // (or the last of u0 .. u{n-1}).
  {
    const s = $('colorBy');
    names.forEach((name, j) => { if (j < axes) s.add(new Option(name, j)); });
    s.add(new Option('component', 'component'));
    s.add(new Option('plain', 'plain'));
    const wanted = params.get('colour') || params.get('color');
    const byName = names.indexOf(wanted), byU = /^u\d+$/.test(wanted || '') ? first + +wanted.slice(1) : -1;
    s.value = wanted === 'component' || wanted === 'plain' ? wanted
      : byName >= 0 && byName < axes ? byName : byU >= first && byU < axes ? byU
      : components > 1 ? 'component' : colourDefault();
    if (MAPS[params.get('map')]) $('colormap').value = params.get('map');
  }

  /** u3 (or the last coordinate); for k >= 3 the one before it when the slice is along it. */
  function colourDefault() {
    const c = first + Math.min(3, data.n - 1);
    return k >= 3 && c === sliceAxis() && c > 0 ? c - 1 : c;
  }

  const plane = () => [+$('planeI').value, +$('planeJ').value];
  /** R from the controls: the slider's angle in the chosen plane, composed with the rotation so far. */
  function rotationFromControls() {
    const [i, j] = plane(), deg = +$('angle').value;
    $('angleText').textContent = deg + '°';
    R = i === j ? base : rotated(base, i, j, (deg * Math.PI) / 180);
  }
  rotationFromControls();
  function commitRotation() { base = R; $('angle').value = 0; $('angleText').textContent = '0°'; }
  [0, 1, 2].forEach((m) => $('axis' + m).addEventListener('change', () => {
    axis[m] = +$('axis' + m).value;
    updatePositions();
  }));
  ['planeI', 'planeJ'].forEach((id) => $(id).addEventListener('change', commitRotation));
  $('angle').addEventListener('input', () => {
    rotationFromControls();
    updatePositions();
  });
  $('reset').addEventListener('click', () => { R = identity(); commitRotation(); updatePositions(); });
  $('colorBy').addEventListener('change', updateColours);
  $('colormap').addEventListener('change', updateColours);
  ['showSingular', 'showUncertified', 'showWire', 'showTriad'].forEach((id) =>
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
    updateTriad();
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

  /** The mesh over the whole canvas, then the triad in its corner. */
  function draw() {
    const w = renderer.domElement.clientWidth, h = renderer.domElement.clientHeight;
    renderer.setScissorTest(false);
    renderer.setViewport(0, 0, w, h);
    renderer.clear();
    renderer.render(scene, camera);
    if (triadScene.visible) {
      renderer.clearDepth();
      renderer.setScissorTest(true);
      renderer.setScissor(w - TRIAD - 10, 10, TRIAD, TRIAD);
      renderer.setViewport(w - TRIAD - 10, 10, TRIAD, TRIAD);
      renderer.render(triadScene, triadCamera);
      renderer.setScissorTest(false);
      renderer.setViewport(0, 0, w, h);
    }
  }

  /** The canvas as a PNG (a data: URL), drawn afresh. */
  function exportPng() {
    draw();
    return renderer.domElement.toDataURL('image/png');
  }
  window.ndcExportPng = exportPng;
  $('savePng').addEventListener('click', () => {
    const link = document.createElement('a');
    link.href = exportPng();
    link.download = String(summary.problem || data.source || 'ndcontour').replace(/[^\w.-]+/g, '_') + '.png';
    document.body.appendChild(link);
    link.click();
    link.remove();
  });

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
  const simplexName = k === 1 ? 'segments' : k === 2 ? 'triangles' : k === 3 ? 'tetrahedra' : k + '-simplices';
  const rows = [
    ['vertices', V], [simplexName, count],
    ['components', mesh.components], ['Euler characteristic', mesh.euler_characteristic],
    ['topology', topology.certified === undefined ? '?' :
      topology.certified ? 'certified' : 'not certified' + (topology.reason ? ': ' + topology.reason : '')],
    ['singular points', singular.length], ['uncertified cells', cells.length],
    ['uncertified simplices', bads]];
  $('info').innerHTML = rows.filter((r) => r[1] !== undefined)
    .map((r) => `<div><b>${r[0]}</b>: ${String(r[1]).replace(/</g, '&lt;')}</div>`).join('') +
    (k >= 3 ? '<div><b>dimension</b>: k = ' + k + ' in R<sup>' + data.n + '</sup></div><div><b>shown</b>: <span id="shown"></span></div>' : '');

  /** k >= 3: what the slice or the skeleton shows, in the panel and in window.ndcView. */
  function showCounts() {
    const now = drawn();
    $('shown').textContent = now.mode === 'skeleton'
      ? `the skeleton: ${now.segments} edges of the ${count} ${simplexName}`
      : `the slice ${now.slice.axis} = ${Number(now.slice.value).toPrecision(3)}: ${now.slice.simplices} ` +
        `${simplexName} cut, ` + (k === 3 ? `${now.triangles} triangles` : `${now.segments} segments`);
    if (window.ndcView.ready) publish(now);
  }
  $('singularText').textContent = 'singular point (' + singular.length + ')';
  $('uncertifiedText').textContent = 'uncertified cell (' + cells.length + ': cubes at the centres; ' +
    bads + (k === 2 ? ' triangles' : k === 1 ? ' segments' : ' ' + simplexName) + ' inside)';

  // An empty result: say so where the mesh would be.
  let message = '';
  if (V === 0) {
    message = emptyZeroSet
      ? 'The zero set does not meet the domain: the subdivision excluded every cell, so there ' +
        'is nothing to draw (summary.json: diagnostics.empty_zero_set).'
      : 'The mesh of this result has no vertices: there is nothing to draw.';
    $('message').innerHTML = '<b>Empty result</b>';
    $('message').appendChild(document.createTextNode(message));
    $('message').hidden = false;
  }

  // --- Go ----------------------------------------------------------------------------------
  resize();
  if (k >= 3) updateSlice();
  updatePositions();
  updateColours();
  updateVisibility();
  let firstFrame = true;
  function frame(time) {
    if ($('tour').checked) tourStep(time);
    if (dirty) {
      draw();
      dirty = false;
      if (firstFrame) {
        firstFrame = false;
        publish({ ready: true, n: data.n, k: k, vertices: V, dimensions: d, simplices: simplices,
                  ...drawn(), uncertified: bads, singular: markers.length,
                  uncertifiedCells: cellMarks.count,
                  names: names.slice(0, axes), components: components, colour: colourMode(),
                  triad: triadState(), rotation: R.map((row) => Array.from(row)),
                  controls: { shown: [0, 1, 2].map((m) => +$('axis' + m).value), plane: plane(),
                              angle: +$('angle').value, angleText: $('angleText').textContent },
                  view: group.quaternion.toArray(),
                  empty: V === 0, message: message,
                  canvas: [renderer.domElement.width, renderer.domElement.height] });
        // #png in the address: the PNG export, for tests (docs/viewer.md).
        if (params.has('png')) publish({ png: exportPng() });
      }
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
