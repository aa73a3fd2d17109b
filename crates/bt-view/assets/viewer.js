// beamtrace viewer: draws the embedded document (scene surfaces, diffracting edges, TX/RX,
// paths and their diffraction points per time step) with the inlined three.js. Names are data: they reach the page only through textContent.
(function () {
  "use strict";
  var doc = JSON.parse(document.getElementById("beamtrace-data").textContent);
  var ORDER_COLOURS = ["#000000", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"];
  function orderColour(order) {
    return ORDER_COLOURS[Math.min(order, ORDER_COLOURS.length - 1)];
  }
  // Colour by loss: viridis from the weakest (dark) to the strongest path (yellow) of the
  // whole document, so colours compare across time steps.
  var VIRIDIS = ["#440154", "#46327e", "#365c8d", "#277f8e", "#1fa187", "#4ac16d", "#a0da39", "#fde725"];
  var losses = [];
  doc.steps.forEach(function (s) { s.paths.forEach(function (p) { losses.push(p.loss_db); }); });
  var lossMin = losses.length ? Math.min.apply(null, losses) : 0;
  var lossMax = losses.length ? Math.max.apply(null, losses) : 1;
  var colourBy = "order";
  function pathColour(p) {
    if (colourBy === "order") return orderColour(p.order);
    var t = lossMax > lossMin ? (lossMax - p.loss_db) / (lossMax - lossMin) : 1;
    return VIRIDIS[Math.min(VIRIDIS.length - 1, Math.floor(t * VIRIDIS.length))];
  }
  var EDGE_COLOUR = "#202020";       // a wedge (two faces)
  var FREE_EDGE_COLOUR = "#6e6e6e";  // a free edge (a screen's boundary)
  var DIFFRACTION_COLOUR = "#f0a000";
  function counted(n, noun) { return n + " " + noun + (n === 1 ? "" : "s"); }
  function text(el, s) { el.textContent = s; return el; }
  function make(tag, s) { return text(document.createElement(tag), s); }

  var container = document.getElementById("view");
  var renderer = new THREE.WebGLRenderer({ antialias: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.setClearColor(0xf4f4f4);
  container.appendChild(renderer.domElement);

  var scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 1.6));
  var sun = new THREE.DirectionalLight(0xffffff, 1.4);
  sun.position.set(3, -4, 8);
  scene.add(sun);
  var camera = new THREE.PerspectiveCamera(50, window.innerWidth / window.innerHeight, 0.01, 1000);
  camera.up.set(0, 0, 1);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);

  // Everything of one step lives in this group; a step change rebuilds it.
  var stepGroup = new THREE.Group();
  scene.add(stepGroup);
  var pathLines = [];
  var state = { steps: doc.steps.length, step: 0, pathLines: 0, paths: 0, surfaces: 0,
                edges: 0, diffractionPoints: 0, ready: false };
  window.beamtraceView = state;

  // A planar polygon as triangles: project on its plane (Newell normal) and triangulate, so
  // concave outlines are filled correctly.
  function polygonGeometry(vertices) {
    var n = new THREE.Vector3();
    for (var i = 0; i < vertices.length; i++) {
      var a = vertices[i], b = vertices[(i + 1) % vertices.length];
      n.x += (a[1] - b[1]) * (a[2] + b[2]);
      n.y += (a[2] - b[2]) * (a[0] + b[0]);
      n.z += (a[0] - b[0]) * (a[1] + b[1]);
    }
    n.normalize();
    var u = Math.abs(n.x) < 0.9 ? new THREE.Vector3(1, 0, 0) : new THREE.Vector3(0, 1, 0);
    u.cross(n).normalize();
    var v = new THREE.Vector3().crossVectors(n, u);
    var flat = vertices.map(function (p) {
      var q = new THREE.Vector3(p[0], p[1], p[2]);
      return new THREE.Vector2(q.dot(u), q.dot(v));
    });
    var faces = THREE.ShapeUtils.triangulateShape(flat, []);
    var positions = [];
    faces.forEach(function (f) {
      f.forEach(function (k) { positions.push(vertices[k][0], vertices[k][1], vertices[k][2]); });
    });
    var g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(positions, 3));
    g.computeVertexNormals();
    return g;
  }

  function lineGeometry(points) {
    var flat = [];
    points.forEach(function (p) { flat.push(p[0], p[1], p[2]); });
    var g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(flat, 3));
    return g;
  }

  // A sphere; with diamond set, four by two segments: an octahedron, flat-shaded.
  function marker(p, colour, radius, diamond) {
    var m = new THREE.Mesh(diamond ? new THREE.SphereGeometry(radius, 4, 2) : new THREE.SphereGeometry(radius, 20, 14),
                           new THREE.MeshLambertMaterial({ color: colour, flatShading: !!diamond }));
    m.position.set(p[0], p[1], p[2]);
    return m;
  }

  // Markers scale with the step's size (0.6 % of its diagonal, at least 6 cm) so they stay
  // visible on a street as in a room.
  function markerRadius(step) {
    var box = new THREE.Box3();
    step.surfaces.forEach(function (s) {
      s.vertices.forEach(function (v) { box.expandByPoint(new THREE.Vector3(v[0], v[1], v[2])); });
    });
    [step.tx, step.rx].forEach(function (v) { if (v) box.expandByPoint(new THREE.Vector3(v[0], v[1], v[2])); });
    return box.isEmpty() ? 0.06 : Math.max(0.06, 0.006 * box.getSize(new THREE.Vector3()).length());
  }

  // three's LineSegments (many segments, one draw call) is not exported by the vendored
  // bundle; GridHelper extends it, so it is taken from there (one Line per edge otherwise).
  var LineSegments = Object.getPrototypeOf(THREE.GridHelper);
  if (!LineSegments.prototype || !LineSegments.prototype.isLineSegments) LineSegments = null;

  // The step's edges of one kind (free or wedge) as thin lines, drawn after the surfaces'
  // outlines they lie on (renderOrder) so they show where they coincide.
  function addEdges(edges, free, colour) {
    var segments = edges.filter(function (e) { return e.free === free; }).map(function (e) { return e.segment; });
    if (!segments.length) return;
    var material = new THREE.LineBasicMaterial({ color: colour });
    var lines = LineSegments
      ? [new LineSegments(lineGeometry([].concat.apply([], segments)), material)]
      : segments.map(function (s) { return new THREE.Line(lineGeometry(s), material); });
    lines.forEach(function (l) { l.renderOrder = 1; stepGroup.add(l); });
  }

  // A diamond at each diffraction point of the step's paths; returns how many.
  function addDiffractionPoints(paths, radius) {
    var count = 0;
    paths.forEach(function (p) {
      (p.interactions || []).forEach(function (kind, i) {
        if (kind !== "diffraction") return;
        stepGroup.add(marker(p.points[i], DIFFRACTION_COLOUR, radius, true));
        count++;
      });
    });
    return count;
  }

  function clearGroup() {
    stepGroup.traverse(function (o) {
      if (o.geometry) o.geometry.dispose();
      if (o.material) o.material.dispose();
    });
    stepGroup.clear();
    pathLines = [];
  }

  function buildStep(k) {
    clearGroup();
    var step = doc.steps[k];
    step.surfaces.forEach(function (s) {
      var blocker = s.kind === "blocker";
      var mesh = new THREE.Mesh(polygonGeometry(s.vertices), new THREE.MeshLambertMaterial({
        color: s.colour, transparent: true, opacity: blocker ? 0.55 : 0.18,
        side: THREE.DoubleSide, depthWrite: false }));
      stepGroup.add(mesh);
      var edge = new THREE.LineLoop(lineGeometry(s.vertices),
                                    new THREE.LineBasicMaterial({ color: s.colour }));
      stepGroup.add(edge);
    });
    addEdges(step.edges, false, EDGE_COLOUR);
    addEdges(step.edges, true, FREE_EDGE_COLOUR);
    step.paths.forEach(function (p) {
      var pts = [step.tx].concat(p.points, [step.rx]);
      var line = new THREE.Line(lineGeometry(pts), new THREE.LineBasicMaterial({
        color: pathColour(p), transparent: true, opacity: p.order === 0 ? 1 : 0.75 }));
      line.userData.path = p;
      stepGroup.add(line);
      pathLines.push(line);
    });
    var radius = markerRadius(step);
    var diffractions = addDiffractionPoints(step.paths, 1.2 * radius);
    // Bare geometry (a mesh without terminals) has no markers: tx and rx are null.
    if (step.tx) { stepGroup.add(marker(step.tx, 0xd62728, radius)); }
    if (step.rx) { stepGroup.add(marker(step.rx, 0x1f77b4, radius)); }
    state.step = k;
    state.pathLines = pathLines.length;
    state.paths = step.paths.length;
    state.surfaces = step.surfaces.length;
    state.edges = step.edges.length;
    state.diffractionPoints = diffractions;
    var edges = counted(step.edges.length, "diffracting edge") +
      (step.edges.length < step.edge_count ? " (of " + step.edge_count + ")" : "");
    text(document.getElementById("counts"),
         counted(step.surfaces.length, "surface") + ", " + edges + ", " +
         counted(step.paths.length, "path") + ", " + counted(diffractions, "diffraction point") +
         (doc.steps.length > 1 ? " (step " + k + " of " + (doc.steps.length - 1) + ")" : ""));
    text(document.getElementById("step-label"), String(k));
  }

  function frame() {
    var box = new THREE.Box3().setFromObject(stepGroup);
    var centre = box.getCenter(new THREE.Vector3());
    var size = box.getSize(new THREE.Vector3()).length() || 1;
    controls.target.copy(centre);
    camera.position.set(centre.x - 0.6 * size, centre.y - 0.95 * size, centre.z + 0.75 * size);
    camera.near = size / 1000;
    camera.far = size * 20;
    camera.updateProjectionMatrix();
    controls.update();
  }

  function swatchRow(colour, cls, label) {
    var row = document.createElement("div");
    var sw = make("span", "");
    sw.className = cls;
    sw.style.background = colour;
    row.appendChild(sw);
    row.appendChild(document.createTextNode(label));
    return row;
  }

  function legend() {
    var paths = document.getElementById("legend-paths");
    paths.replaceChildren();
    if (colourBy === "order") {
      var orders = {};
      doc.steps.forEach(function (s) { s.paths.forEach(function (p) { orders[p.order] = true; }); });
      Object.keys(orders).map(Number).sort(function (a, b) { return a - b; }).forEach(function (o) {
        paths.appendChild(swatchRow(orderColour(o), "swatch", o === 0 ? "line of sight" : "order " + o));
      });
    } else {
      paths.appendChild(swatchRow(VIRIDIS[VIRIDIS.length - 1], "swatch", "loss " + lossMin.toFixed(1) + " dB"));
      paths.appendChild(swatchRow(VIRIDIS[0], "swatch", "loss " + lossMax.toFixed(1) + " dB"));
    }
  }

  function surfaceLegend() {
    var el = document.getElementById("legend-surfaces");
    doc.materials.forEach(function (m) { el.appendChild(swatchRow(m.colour, "box", m.name)); });
    el.appendChild(swatchRow("#e15759", "box", "blocker"));
  }

  // Edge and diffraction rows, for what some step of the document has.
  function edgeLegend() {
    var el = document.getElementById("legend-edges");
    var has = function (test) { return doc.steps.some(test); };
    if (has(function (s) { return s.edges.some(function (e) { return !e.free; }); })) {
      el.appendChild(swatchRow(EDGE_COLOUR, "line", "diffracting edge"));
    }
    if (has(function (s) { return s.edges.some(function (e) { return e.free; }); })) {
      el.appendChild(swatchRow(FREE_EDGE_COLOUR, "line", "diffracting edge (free)"));
    }
    if (has(function (s) { return s.paths.some(function (p) { return (p.interactions || []).indexOf("diffraction") >= 0; }); })) {
      el.appendChild(swatchRow(DIFFRACTION_COLOUR, "diamond", "diffraction point"));
    }
  }

  // Hover: the nearest path line under the pointer, its numbers in the tip.
  var raycaster = new THREE.Raycaster();
  var pointer = new THREE.Vector2();
  var tip = document.getElementById("tip");
  var highlighted = null;
  function describe(p) {
    var f = function (x, d) { return Number(x).toFixed(d); };
    return [
      p.order === 0 ? "line of sight" : "order " + p.order + ": " + p.surfaces.map(function (s, i) {
        return (p.interactions || [])[i] === "diffraction" ? "edge " + s : s;
      }).join(" > "),
      "length " + f(p.length_m, 3) + " m, delay " + f(p.delay_s * 1e9, 3) + " ns",
      "AoD az " + f(p.aod_deg.azimuth, 2) + " deg, el " + f(p.aod_deg.elevation, 2) + " deg",
      "AoA az " + f(p.aoa_deg.azimuth, 2) + " deg, el " + f(p.aoa_deg.elevation, 2) + " deg",
      "loss " + f(p.loss_db, 2) + " dB"
    ].join("\n");
  }
  function onPointer(event) {
    pointer.x = (event.clientX / window.innerWidth) * 2 - 1;
    pointer.y = -(event.clientY / window.innerHeight) * 2 + 1;
    raycaster.params.Line.threshold = 0.03 * camera.position.distanceTo(controls.target) / 5;
    raycaster.setFromCamera(pointer, camera);
    var hits = raycaster.intersectObjects(pathLines, false);
    if (highlighted) { highlighted.material.linewidth = 1; highlighted.material.color.set(pathColour(highlighted.userData.path)); }
    highlighted = null;
    if (hits.length) {
      highlighted = hits[0].object;
      highlighted.material.color.set(0xff00ff);
      text(tip, describe(highlighted.userData.path));
      tip.style.display = "block";
      tip.style.left = (event.clientX + 14) + "px";
      tip.style.top = (event.clientY + 14) + "px";
    } else {
      tip.style.display = "none";
    }
  }
  renderer.domElement.addEventListener("pointermove", onPointer);

  window.addEventListener("resize", function () {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
  });

  text(document.getElementById("title"), doc.scene);
  legend();
  surfaceLegend();
  edgeLegend();
  document.getElementById("colour-by").addEventListener("change", function (e) {
    colourBy = e.target.value;
    pathLines.forEach(function (l) { l.material.color.set(pathColour(l.userData.path)); });
    legend();
  });
  // Pixel position of a world point (metres), for tests that hover a path.
  state.project = function (p) {
    var v = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
    return [(v.x + 1) / 2 * window.innerWidth, (1 - v.y) / 2 * window.innerHeight];
  };
  var slider = document.getElementById("step");
  if (doc.steps.length > 1) {
    slider.max = String(doc.steps.length - 1);
    document.getElementById("stepper").hidden = false;
    slider.addEventListener("input", function () { buildStep(Number(slider.value)); });
  }
  buildStep(0);
  frame();
  renderer.setAnimationLoop(function () {
    controls.update();
    renderer.render(scene, camera);
  });
  state.ready = true;
})();
