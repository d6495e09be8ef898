// The report page's 3D view, timeline and plot link. Reads the JSON in #data; reports its state in
// document.title ("ok <ms> ms" after the first frame, "error: ..." on any error) so a headless
// browser can check it.
"use strict";
(function () {
  const fail = (message) => { document.title = "error: " + message; };
  window.addEventListener("error", (e) => fail(e.message || String(e)));
  const consoleError = console.error.bind(console);
  console.error = (...args) => { fail("console: " + args.map(String).join(" ")); consoleError(...args); };

  const data = JSON.parse(document.getElementById("data").textContent);
  const T = THREE;
  const segments = data.segments;
  const clockMax = Math.max(segments.length, 1e-9);

  function decode(text, Type) {
    const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
    return new Type(bytes.buffer);
  }
  function geometry(g) {
    const geo = new T.BufferGeometry();
    geo.setAttribute("position", new T.BufferAttribute(decode(g.positions, Float32Array), 3));
    geo.setIndex(new T.BufferAttribute(decode(g.indices, Uint32Array), 1));
    return geo;
  }
  function placeOf(p) {
    return { position: new T.Vector3(p[0], p[1], p[2]), quaternion: new T.Quaternion(p[3], p[4], p[5], p[6]) };
  }
  function matrixOf(p) {
    const place = placeOf(p);
    return new T.Matrix4().compose(place.position, place.quaternion, new T.Vector3(1, 1, 1));
  }

  const canvas = document.getElementById("three");
  const renderer = new T.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setClearColor(0xffffff, 1);
  const scene = new T.Scene();
  scene.add(new T.HemisphereLight(0xffffff, 0x8a8a80, 1.6));
  const sun = new T.DirectionalLight(0xffffff, 1.6);
  sun.position.set(2, -3, 4);
  scene.add(sun);

  const colours = { link: [0xb8bdc4, 0x808794], obstacle: 0x5c8fd1, blocked: 0xe01f24, contact: 0x8c564b, closest: 0x1accd9 };
  const bodies = new Map(); // name -> { materials, base }
  function material(name, colour, opacity) {
    const m = new T.MeshLambertMaterial({ color: colour, flatShading: true, side: T.DoubleSide, transparent: opacity < 1, opacity });
    if (!bodies.has(name)) bodies.set(name, []);
    bodies.get(name).push({ material: m, base: colour });
    return m;
  }

  // Robot: one group per link, its shapes at their poses in it.
  const linkGroups = data.robot.links.map((link, i) => {
    const group = new T.Group();
    group.matrixAutoUpdate = false;
    const m = material(link.name, colours.link[i % 2], 1);
    for (const shape of link.shapes) {
      const mesh = new T.Mesh(geometry(shape.geometry), m);
      const place = placeOf(shape.pose);
      mesh.position.copy(place.position);
      mesh.quaternion.copy(place.quaternion);
      group.add(mesh);
    }
    scene.add(group);
    return group;
  });
  const box = { min: new T.Vector3(Infinity, Infinity, Infinity), max: new T.Vector3(-Infinity, -Infinity, -Infinity) };
  const grow = (v) => { box.min.min(v); box.max.max(v); };
  for (const obstacle of data.obstacles) {
    const mesh = new T.Mesh(geometry(obstacle.geometry), material(obstacle.name, colours.obstacle, 0.8));
    const place = placeOf(obstacle.pose);
    mesh.position.copy(place.position);
    mesh.quaternion.copy(place.quaternion);
    scene.add(mesh);
    mesh.geometry.computeBoundingBox();
    const b = mesh.geometry.boundingBox.clone().applyMatrix4(matrixOf(obstacle.pose));
    grow(b.min); grow(b.max);
  }
  // Goal frames (x red, y green, z blue) in one draw call, plus a cross on each goal not reached.
  const goalPositions = [];
  const goalColours = [];
  const axisColours = [[0.84, 0.15, 0.16], [0.17, 0.63, 0.17], [0.12, 0.47, 0.71]];
  const outcomeColour = { reached: [0.17, 0.63, 0.17], no_path: [1, 0.5, 0.05], unreachable: [0.84, 0.15, 0.16] };
  for (const goal of data.goals) {
    const p = new T.Vector3(...goal.position);
    grow(p);
    const q = new T.Quaternion(...goal.rotation);
    [[1, 0, 0], [0, 1, 0], [0, 0, 1]].forEach((axis, k) => {
      const end = new T.Vector3(...axis).multiplyScalar(0.05).applyQuaternion(q).add(p);
      goalPositions.push(p.x, p.y, p.z, end.x, end.y, end.z);
      goalColours.push(...axisColours[k], ...axisColours[k]);
    });
    if (goal.outcome !== "reached") {
      const c = outcomeColour[goal.outcome] || [0.5, 0.5, 0.5];
      for (const [dx, dy] of [[1, 1], [1, -1]]) {
        goalPositions.push(p.x - 0.02 * dx, p.y - 0.02 * dy, p.z, p.x + 0.02 * dx, p.y + 0.02 * dy, p.z);
        goalColours.push(...c, ...c);
      }
    }
  }
  if (goalPositions.length) {
    const geo = new T.BufferGeometry();
    geo.setAttribute("position", new T.Float32BufferAttribute(goalPositions, 3));
    geo.setAttribute("color", new T.Float32BufferAttribute(goalColours, 3));
    scene.add(new T.LineSegments(geo, new T.LineBasicMaterial({ vertexColors: true })));
  }

  // Forward kinematics, as the model stage does it: link i+1 = link i * origin * motion(q_i).
  const base = matrixOf(data.robot.base);
  const origins = data.robot.joints.map((j) => matrixOf(j.origin));
  const toolOffset = matrixOf(data.robot.tool);
  function forward(q) {
    const frames = [base.clone()];
    data.robot.joints.forEach((joint, i) => {
      const axis = new T.Vector3(...joint.axis);
      const motion = joint.prismatic
        ? new T.Matrix4().makeTranslation(axis.x * q[i], axis.y * q[i], axis.z * q[i])
        : new T.Matrix4().makeRotationFromQuaternion(new T.Quaternion().setFromAxisAngle(axis, q[i]));
      frames.push(frames[i].clone().multiply(origins[i]).multiply(motion));
    });
    return frames;
  }
  function configuration(clock) {
    if (!segments.length) return data.home;
    const k = Math.min(Math.floor(clock), segments.length - 1);
    const s = Math.min(clock - k, 1);
    const seg = segments[k];
    return seg.from.map((a, i) => a + s * (seg.to[i] - a));
  }

  // The page's kinematics against ours, before anything is shown.
  for (const check of data.checks) {
    const frames = forward(configuration(check.clock));
    const tool = new T.Vector3().setFromMatrixPosition(frames[frames.length - 1].clone().multiply(toolOffset));
    const error = tool.distanceTo(new T.Vector3(...check.tool));
    // f32 matrices in three.js: micrometres over a metre-sized arm.
    if (!(error < 1e-4)) throw new Error("page kinematics differ from the report's by " + error + " m at clock " + check.clock);
  }

  for (const frame of forward(data.home)) grow(new T.Vector3().setFromMatrixPosition(frame));
  if (!isFinite(box.min.x)) { box.min.set(-1, -1, 0); box.max.set(1, 1, 1); }
  const centre = box.min.clone().add(box.max).multiplyScalar(0.5);
  const size = Math.max(box.max.clone().sub(box.min).length(), 0.5);
  if (data.floor !== null) {
    const grid = new T.GridHelper(Math.ceil(size * 2), Math.ceil(size * 2) * 10, 0x999990, 0xd8d8d0);
    grid.rotation.x = Math.PI / 2;
    grid.position.set(centre.x, centre.y, data.floor);
    scene.add(grid);
  }
  const camera = new T.PerspectiveCamera(40, 1, size / 100, size * 20);
  camera.up.set(0, 0, 1);
  // Framed: the sphere around robot, obstacles and goals just fills the 40 degree view (5 % to
  // spare), rather than starting half again as far out.
  const distance = (1.05 * size / 2) / Math.sin((20 * Math.PI) / 180);
  camera.position.copy(centre).add(new T.Vector3(1.2, -1.6, 0.9).normalize().multiplyScalar(distance));
  const controls = new T.OrbitControls(camera, canvas);
  controls.target.copy(centre);
  controls.update();

  // Timeline: robot pose, highlighted pairs, status line, plot cursor, table row.
  const slider = document.getElementById("clock");
  slider.max = String(segments.length || 1);
  const label = document.getElementById("clock-label");
  const status = document.getElementById("status");
  const plot = document.querySelector("#plot svg");
  let cursor = null;
  if (plot) {
    cursor = document.createElementNS("http://www.w3.org/2000/svg", "line");
    cursor.setAttribute("stroke", "#000");
    cursor.setAttribute("stroke-width", "1.5");
    cursor.setAttribute("y1", "60");
    cursor.setAttribute("y2", "384");
    plot.appendChild(cursor);
    plot.addEventListener("click", (event) => {
      const point = plot.createSVGPoint();
      point.x = event.clientX; point.y = event.clientY;
      const local = point.matrixTransform(plot.getScreenCTM().inverse());
      const left = Number(plot.dataset.left), right = Number(plot.dataset.right);
      setClock(((local.x - left) / (right - left)) * segments.length);
    });
  }
  const rows = new Map();
  for (const row of document.querySelectorAll("tr[data-goal]")) {
    rows.set(Number(row.dataset.goal), row);
    row.addEventListener("click", () => goTo(Number(row.dataset.goal)));
  }
  function goTo(goal) {
    let last = -1;
    segments.forEach((seg, k) => { if (seg.goal === goal) last = k; });
    if (last < 0) return;
    const touch = segments[last].touch;
    setClock(last + (touch ? touch.s : 1) - 1e-6);
  }

  let clock = 0;
  let currentRow = null;
  function setClock(value) {
    clock = Math.min(Math.max(value, 0), segments.length ? segments.length - 1e-6 : 0);
    slider.value = String(clock);
    const frames = forward(configuration(clock));
    linkGroups.forEach((group, i) => { group.matrix.copy(frames[i]); group.matrixWorldNeedsUpdate = true; });
    for (const list of bodies.values()) for (const entry of list) entry.material.color.setHex(entry.base);
    const paint = (name, colour) => { for (const entry of bodies.get(name) || []) entry.material.color.setHex(colour); };
    let text = "home";
    if (segments.length) {
      const k = Math.min(Math.floor(clock), segments.length - 1);
      const s = clock - k;
      const seg = segments[k];
      const goal = data.goals[seg.goal] || { name: "?" };
      text = `segment ${k} to goal ${seg.goal} ${goal.name}${seg.planned ? "" : " (blocked attempt)"}, s = ${s.toFixed(3)}`;
      if (seg.bound !== null) {
        const kinds = [["obstacles", seg.by_kind.obstacles_m], ["self", seg.by_kind.self_m], ["floor", seg.by_kind.floor_m]]
          .filter(([, bound]) => bound !== null)
          .map(([kind, bound]) => `${kind} ${(bound * 1000).toFixed(1)}`);
        text += `\ncertified clearance >= ${(seg.bound * 1000).toFixed(1)} mm (${kinds.join(", ")})`;
      }
      if (seg.closest) {
        paint(seg.closest.a, colours.closest); paint(seg.closest.b, colours.closest);
        text += `\nclosest: ${seg.closest.a} and ${seg.closest.b}, ${(seg.closest.distance * 1000).toFixed(1)} mm at s = ${seg.closest.s.toFixed(3)}`;
      }
      for (const contact of data.contacts) {
        if (clock >= contact.start && clock <= contact.end) {
          paint(contact.a, colours.contact); paint(contact.b, colours.contact);
          text += `\n${contact.engine} contact: ${contact.a} and ${contact.b}`;
        }
      }
      if (seg.touch && s >= seg.touch.s) {
        paint(seg.touch.a, colours.blocked); paint(seg.touch.b, colours.blocked);
        text += `\nBLOCKED at s = ${seg.touch.s.toFixed(3)}: ${seg.touch.a} and ${seg.touch.b}, ${(seg.touch.distance * 1000).toFixed(1)} mm`;
      }
      if (currentRow) currentRow.classList.remove("current");
      currentRow = rows.get(seg.goal) || null;
      if (currentRow) currentRow.classList.add("current");
    }
    status.textContent = text;
    label.textContent = `clock ${clock.toFixed(3)} / ${segments.length}`;
    if (cursor) {
      const left = Number(plot.dataset.left), right = Number(plot.dataset.right);
      const x = left + (right - left) * (segments.length ? clock / segments.length : 0);
      cursor.setAttribute("x1", String(x)); cursor.setAttribute("x2", String(x));
    }
    render();
  }
  slider.addEventListener("input", () => { playing = false; setClock(Number(slider.value)); });

  let playing = false;
  let last = 0;
  const rate = Math.min(Math.max(segments.length / 20, 1), 50); // segments per second
  const play = document.getElementById("play");
  play.addEventListener("click", () => {
    playing = !playing;
    play.textContent = playing ? "pause" : "play";
    if (playing && clock >= segments.length - 1e-3) setClock(0);
    last = performance.now();
    if (playing) requestAnimationFrame(step);
  });
  function step(now) {
    if (!playing) return;
    setClock(clock + ((now - last) / 1000) * rate);
    last = now;
    if (clock >= segments.length - 1e-5) { playing = false; play.textContent = "play"; return; }
    requestAnimationFrame(step);
  }

  function render() {
    const width = canvas.clientWidth, height = canvas.clientHeight;
    if (canvas.width !== width || canvas.height !== height) {
      renderer.setSize(width, height, false);
      camera.aspect = width / Math.max(height, 1);
      camera.updateProjectionMatrix();
    }
    renderer.render(scene, camera);
  }
  controls.addEventListener("change", render);
  window.addEventListener("resize", render);

  setClock(0);
  if (!document.title.startsWith("error")) document.title = "ok " + Math.round(performance.now()) + " ms";
})();
