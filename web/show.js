// dicesim show: the die in 3-D (turnable, labels on its faces, material regions tinted, centre of
// mass marked) and, with a toss, its animation. Reads the JSON in #dicesim-data; needs THREE only.
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('dicesim-data').textContent);
  const die = D.die, toss = D.toss || null, info = D.info || {};
  const $ = (id) => document.getElementById(id);
  const fmt = (x, d) => (typeof x === 'number' ? Number(x.toPrecision(d || 4)).toString() : String(x));
  const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);

  // ---- text: title, outcome, info tables ------------------------------------------------------
  $('title').textContent = (D.scene || '') + (die.name ? ' \u2014 ' + die.name : '');
  if (toss) {
    const ok = toss.status === 'settled';
    $('outcome').innerHTML = 'Toss ' + toss.index + ' (seed ' + toss.seed + ', ' + esc(toss.fidelity) + '): ' +
      (ok ? 'outcome <b id="outcome-label">' + esc(toss.outcome) + '</b>' : '<b id="outcome-label">' + esc(toss.status) + '</b> (no outcome)') +
      ' after ' + fmt(toss.t_end, 3) + ' s, ' + toss.bounces + ' impacts';
  } else {
    $('outcome').textContent = 'No toss shown (dicesim show SCENE --toss I animates one).';
  }
  const rows = [
    ['shape', info.shape + (info.convex === false ? ' (not convex: contact uses its hull)' : '')],
    ['fidelity', info.fidelity + (info.fidelity_reason ? ' \u2014 ' + info.fidelity_reason : '')],
    ['mass', fmt(info.mass * 1e3, 6) + ' g'],
    ['centre of mass', (info.com || []).map((c) => fmt(c * 1e3, 4)).join(', ') + ' mm from the geometric centre'],
    ['principal moments', (info.principal_moments || []).map((c) => fmt(c, 4)).join(', ') + ' kg m\u00b2'],
    ['bounding radius', fmt(info.bounding_radius * 1e3, 4) + ' mm'],
    ['rounding', fmt((info.rounding || 0) * 1e3, 4) + ' mm'],
    ['read', info.read || ''],
    ['material', die.base_material + (die.regions.length ? ' + regions: ' + die.regions.map((r) => r.material).join(', ') : '')],
  ];
  $('info').innerHTML = rows.map((r) => '<tr><th>' + esc(r[0]) + '</th><td>' + esc(r[1]) + '</td></tr>').join('');
  if (info.faces) {
    $('faces').innerHTML = '<tr><th>face</th><th>label</th><th>area (mm\u00b2)</th><th>stable</th><th>p_static</th></tr>' +
      info.faces.map((f, i) => '<tr><td class="n">' + i + '</td><td class="n">' + esc(f.label) + '</td><td class="n">' +
        fmt(f.area * 1e6, 4) + '</td><td>' + (f.stable ? 'yes' : 'no') + '</td><td class="n">' + fmt(f.p_static, 4) + '</td></tr>').join('');
  }
  const regionColors = [0xe07020, 0x2080e0, 0x20b060, 0xc03090, 0x808020];
  $('keys').innerHTML = '<span class="sw" style="background:#d00"></span>centre of mass' +
    (die.com_offset_mm > 1e-6 ? ' &nbsp;<span class="sw" style="background:#777"></span>geometric centre (' + fmt(die.com_offset_mm, 3) + ' mm away)' : '') +
    die.regions.map((r, i) => ' &nbsp;<span class="sw" style="background:#' + regionColors[i % regionColors.length].toString(16).padStart(6, '0') +
      '"></span>' + esc(r.material) + ' region').join('') + (toss ? ' &nbsp;<span class="sw" style="background:#e8b800"></span>face read' : '');

  // ---- 3-D ------------------------------------------------------------------------------------
  const view = $('view');
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    view.innerHTML = '<div id="error">This browser cannot draw WebGL, so the die is not shown: ' + esc(e.message) + '</div>';
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.insertBefore(renderer.domElement, view.firstChild);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f1);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const sun = new THREE.DirectionalLight(0xffffff, 0.65);
  sun.position.set(1, -2, 3);
  scene.add(sun);
  const R = die.bounding_radius;
  const camera = new THREE.PerspectiveCamera(35, 1, R / 50, R * 2000);
  camera.up.set(0, 0, 1);  // the simulation's world: z up

  const V = (a) => new THREE.Vector3(a[0], a[1], a[2]);
  const body = new THREE.Group();  // the die's body frame (principal axes, origin at the COM)
  scene.add(body);
  const faceMeshes = [];
  const translucent = die.regions.length > 0;

  // fontFrac: font size over the texture's side; fitFrac: the widest the text may be (same units).
  function labelTexture(text, px, fontFrac, color, fitFrac) {
    const c = document.createElement('canvas');
    c.width = c.height = px;
    const g = c.getContext('2d');
    g.fillStyle = color;
    g.fillRect(0, 0, px, px);
    g.fillStyle = '#1a1a1a';
    const t = (text === '6' || text === '9') ? text + '.' : text;
    let size = px * fontFrac;
    g.font = 'bold ' + size + 'px sans-serif';
    const w = g.measureText(t).width;
    const fit = px * (fitFrac || 0.8);
    if (w > fit) { size *= fit / w; g.font = 'bold ' + size + 'px sans-serif'; }
    g.textAlign = 'center';
    g.textBaseline = 'middle';
    g.fillText(t, px / 2, px / 2);
    const tex = new THREE.CanvasTexture(c);
    tex.anisotropy = 4;
    return tex;
  }
  function polygonGeometry(points, uvOf) {
    const pos = [], uv = [];
    for (let i = 1; i + 1 < points.length; ++i)
      for (const p of [points[0], points[i], points[i + 1]]) {
        pos.push(p.x, p.y, p.z);
        if (uvOf) uv.push(...uvOf(p));
      }
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    if (uvOf) geo.setAttribute('uv', new THREE.Float32BufferAttribute(uv, 2));
    geo.computeVertexNormals();
    return geo;
  }
  const faceMaterial = (tex) => new THREE.MeshLambertMaterial({ map: tex, side: THREE.FrontSide, transparent: translucent, opacity: translucent ? 0.75 : 1 });

  if (die.kind === 'cylinder') {
    const c = die.cylinder;
    const side = new THREE.MeshLambertMaterial({ color: 0xc9c9c0, transparent: translucent, opacity: translucent ? 0.75 : 1 });
    const heads = faceMaterial(labelTexture(die.faces[0].text, 256, 0.22, '#d8d2b8'));
    const tails = faceMaterial(labelTexture(die.faces[1].text, 256, 0.22, '#d8d2b8'));
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(c.radius, c.radius, 2 * c.half, 96), [side, heads, tails]);
    mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), V(c.axis).normalize());
    mesh.position.copy(V(c.centre));
    body.add(mesh);
    faceMeshes.push({ mesh: mesh, materials: [heads, tails, side] });
  } else {
    const verts = die.vertices.map(V);
    const r = die.rounding;
    die.faces.forEach((f, fi) => {
      const n = V(f.normal).normalize();
      const pts = f.loop.map((v) => verts[v].clone().addScaledVector(n, r));
      const centre = pts.reduce((a, p) => a.add(p), new THREE.Vector3()).multiplyScalar(1 / pts.length);
      const e1 = pts[1].clone().sub(pts[0]).normalize(), e2 = n.clone().cross(e1);
      let half = 0, inr = Infinity;
      for (let i = 0; i < pts.length; ++i) {
        const d = pts[i].clone().sub(centre);
        half = Math.max(half, Math.abs(d.dot(e1)), Math.abs(d.dot(e2)));
        const a = pts[i], b = pts[(i + 1) % pts.length], ab = b.clone().sub(a).normalize();
        const ac = centre.clone().sub(a);
        inr = Math.min(inr, ac.clone().sub(ab.clone().multiplyScalar(ac.dot(ab))).length());
      }
      // Text upright when the face is seen with the body's +z (or the face's first edge) up.
      const up = Math.abs(n.z) < 0.9 ? new THREE.Vector3(0, 0, 1).sub(n.clone().multiplyScalar(n.z)).normalize() : e2;
      const right = up.clone().cross(n).normalize();
      const uvOf = (p) => { const d = p.clone().sub(centre); return [0.5 + d.dot(right) / (2 * half), 0.5 + d.dot(up) / (2 * half)]; };
      // The label inside the face's inscribed circle (diameter inr / half of the texture's side).
      const mat = faceMaterial(labelTexture(f.text, 256, Math.min(0.6, 0.62 * inr / half), '#efe9d6', 0.85 * inr / half));
      const mesh = new THREE.Mesh(polygonGeometry(pts, uvOf), mat);
      body.add(mesh);
      faceMeshes.push({ mesh: mesh, materials: [mat] });
    });
    if (r > 0) {  // the core: shows as the rounded edges' darker bands between the faces
      const coreMat = new THREE.MeshLambertMaterial({ color: 0xb8b2a0, transparent: translucent, opacity: translucent ? 0.75 : 1 });
      die.faces.forEach((f) => body.add(new THREE.Mesh(polygonGeometry(f.loop.map((v) => verts[v])), coreMat)));
    }
  }
  die.regions.forEach((reg, i) => {
    const mat = new THREE.MeshLambertMaterial({ color: regionColors[i % regionColors.length], transparent: true, opacity: 0.6,
      depthWrite: false, polygonOffset: true, polygonOffsetFactor: -2, polygonOffsetUnits: -2, side: THREE.DoubleSide });
    reg.polygons.forEach((poly) => body.add(new THREE.Mesh(polygonGeometry(poly.map(V)), mat)));
  });
  const dot = (color, radius) => new THREE.Mesh(new THREE.SphereGeometry(radius, 16, 12),
    new THREE.MeshBasicMaterial({ color: color, depthTest: false, transparent: true }));
  const com = dot(0xdd0000, 0.05 * R);
  com.renderOrder = 10;
  body.add(com);
  if (die.com_offset_mm > 1e-6) {
    const gc = dot(0x777777, 0.035 * R);
    gc.position.copy(V(die.geometric_centre));
    gc.renderOrder = 10;
    body.add(gc);
  }

  // ---- the floor and the toss's frames ----------------------------------------------------------
  const frames = toss ? toss.frames : [[0, 0, 0, 0, 0, 0, 0, 1]];
  const tEnd = toss ? Math.max(toss.t_end, frames[frames.length - 1][0]) : 0;
  if (toss) {
    let minx = Infinity, maxx = -Infinity, miny = Infinity, maxy = -Infinity;
    for (const f of frames) { minx = Math.min(minx, f[1]); maxx = Math.max(maxx, f[1]); miny = Math.min(miny, f[2]); maxy = Math.max(maxy, f[2]); }
    const size = Math.max(maxx - minx, maxy - miny) + 12 * R;
    const grid = new THREE.GridHelper(size, Math.max(4, Math.round(size / (4 * R))), 0x999999, 0xcccccc);
    grid.rotation.x = Math.PI / 2;
    grid.position.set((minx + maxx) / 2, (miny + maxy) / 2, 0);
    scene.add(grid);
    const floor = new THREE.Mesh(new THREE.PlaneGeometry(size, size), new THREE.MeshLambertMaterial({ color: 0xe4e0d4 }));
    floor.position.set((minx + maxx) / 2, (miny + maxy) / 2, -1e-5);
    scene.add(floor);
  }
  const qa = new THREE.Quaternion(), qb = new THREE.Quaternion();
  function pose(t) {
    let lo = 0, hi = frames.length - 1;
    if (t <= frames[0][0]) hi = 0;
    else if (t >= frames[hi][0]) lo = hi;
    else while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (frames[mid][0] <= t) lo = mid; else hi = mid; }
    const a = frames[lo], b = frames[hi];
    const u = b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 0;
    body.position.set(a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2]), a[3] + u * (b[3] - a[3]));
    qa.set(a[4], a[5], a[6], a[7]);
    qb.set(b[4], b[5], b[6], b[7]);
    body.quaternion.copy(qa.slerp(qb, u));
  }

  // ---- camera: a small orbit control (Debian's three.js ships OrbitControls only as a module) ----
  const orbit = { theta: -Math.PI / 3, phi: 1.05, dist: 5 * R };
  const home = Object.assign({}, orbit);
  const target = new THREE.Vector3();
  // The view follows the die with a lag of ~0.1 s of real time, however few frames a second the
  // browser draws (a per-frame step left the die out of view in a slow, software-drawn browser).
  function placeCamera(dt) {
    if (toss) target.lerp(body.position, 1 - Math.exp(-dt / 0.1));
    const s = Math.sin(orbit.phi);
    camera.position.set(target.x + orbit.dist * s * Math.cos(orbit.theta), target.y + orbit.dist * s * Math.sin(orbit.theta),
      target.z + orbit.dist * Math.cos(orbit.phi));
    camera.lookAt(target);
  }
  let drag = null;
  const el = renderer.domElement;
  el.addEventListener('pointerdown', (e) => { drag = { x: e.clientX, y: e.clientY }; el.setPointerCapture(e.pointerId); });
  el.addEventListener('pointerup', () => { drag = null; });
  el.addEventListener('pointermove', (e) => {
    if (!drag) return;
    orbit.theta -= 0.008 * (e.clientX - drag.x);
    orbit.phi = Math.min(Math.PI - 0.05, Math.max(0.05, orbit.phi - 0.008 * (e.clientY - drag.y)));
    drag = { x: e.clientX, y: e.clientY };
  });
  el.addEventListener('wheel', (e) => { e.preventDefault(); orbit.dist = Math.min(400 * R, Math.max(1.5 * R, orbit.dist * Math.exp(0.001 * e.deltaY))); }, { passive: false });
  el.addEventListener('dblclick', () => Object.assign(orbit, home));

  function resize() {
    const w = view.clientWidth, h = view.clientHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }
  window.addEventListener('resize', resize);
  resize();

  // ---- the player -----------------------------------------------------------------------------
  let t = 0, playing = false, lastMs = null, highlighted = false;
  const hash = new URLSearchParams(location.hash.slice(1));
  function highlight(on) {
    if (!toss || toss.face_index < 0 || on === highlighted) return;
    highlighted = on;
    const fm = die.kind === 'cylinder' ? faceMeshes[0].materials[toss.face_index] : faceMeshes[toss.face_index].materials[0];
    fm.color.set(on ? 0xffd030 : 0xffffff);
    if (fm.emissive) fm.emissive.set(on ? 0x403000 : 0x000000);
  }
  function show(time) {
    t = Math.min(Math.max(time, 0), tEnd);
    pose(t);
    highlight(toss && t >= tEnd);
    if (toss) {
      $('slider').value = String(Math.round(10000 * t / (tEnd || 1)));
      $('clock').textContent = 't = ' + t.toFixed(3) + ' s / ' + tEnd.toFixed(3) + ' s';
      $('now').style.left = (100 * t / (tEnd || 1)) + '%';
    }
  }
  if (toss) {
    $('player').hidden = false;
    const tl = $('timeline');
    const imp = toss.impacts;
    imp.forEach((m, i) => {
      const d = document.createElement('div');
      d.className = 'm ' + m.kind;
      d.style.left = (100 * m.t / (tEnd || 1)) + '%';
      d.title = 'impact ' + (i + 1) + ' at ' + fmt(m.t, 4) + ' s: ' + m.kind + ', energy ' + fmt(m.energy_before * 1e3, 4) + ' \u2192 ' + fmt(m.energy_after * 1e3, 4) + ' mJ';
      tl.appendChild(d);
    });
    const now = document.createElement('div');
    now.className = 'now';
    now.id = 'now';
    tl.appendChild(now);
    tl.addEventListener('click', (e) => { playing = false; $('play').textContent = 'Play'; show(tEnd * (e.clientX - tl.getBoundingClientRect().left) / tl.clientWidth); });
    $('impacts-summary').textContent = imp.length + ' impacts (time, what struck, energy before \u2192 after; energy = kinetic + m g z)';
    $('impacts').innerHTML = '<tr><th>#</th><th>t (s)</th><th>kind</th><th>energy (mJ)</th></tr>' + imp.map((m, i) =>
      '<tr><td class="n">' + (i + 1) + '</td><td class="n">' + m.t.toFixed(4) + '</td><td><span class="k ' + m.kind + '">' + m.kind +
      '</span></td><td class="n">' + fmt(m.energy_before * 1e3, 4) + ' \u2192 ' + fmt(m.energy_after * 1e3, 4) + '</td></tr>').join('');
    $('play').addEventListener('click', () => {
      if (!playing && t >= tEnd) show(0);
      playing = !playing;
      $('play').textContent = playing ? 'Pause' : 'Play';
      lastMs = null;
    });
    $('slider').addEventListener('input', () => { playing = false; $('play').textContent = 'Play'; show(tEnd * $('slider').value / 10000); });
    // #t=end (or a time in s) opens the page paused there, as the tests' screenshots do.
    const start = hash.get('t');
    if (start === 'end') show(tEnd);
    else if (start !== null) show(parseFloat(start) || 0);
    else { show(0); playing = true; $('play').textContent = 'Pause'; }
    target.copy(body.position);
  } else {
    show(0);
  }
  let camMs = null;
  function frame(ms) {
    if (playing && lastMs !== null) {
      show(t + (ms - lastMs) / 1000 * parseFloat($('speed').value));
      if (t >= tEnd) { playing = false; $('play').textContent = 'Replay'; }
    }
    lastMs = ms;
    placeCamera(camMs === null ? 1 : Math.min(1, (ms - camMs) / 1000));
    camMs = ms;
    renderer.render(scene, camera);
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
