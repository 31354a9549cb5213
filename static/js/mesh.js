// The mesh page. Without JavaScript the form posts the file and the server answers with the
// whole page. With it, choosing or dropping a file (or several: a .gltf with its .bin, an
// .obj with its .mtl) uploads it at once with a progress bar (POST /mesh?part=report answers
// with the report alone), the figures are drawn from the report's JSON blocks, and the
// downloads send the files the page still holds to the JSON API again: the server keeps
// nothing between requests. The fixed mesh's download says what its format leaves out.
"use strict";

(function () {
  const form = document.getElementById("mesh-form");
  const input = document.getElementById("mesh-file");
  const dropzone = document.getElementById("mesh-dropzone");
  const progressRow = document.getElementById("mesh-progress-row");
  const progress = document.getElementById("mesh-progress");
  const progressLabel = document.getElementById("mesh-progress-label");
  const progressText = document.getElementById("mesh-progress-text");
  const status = document.getElementById("mesh-status");
  const output = document.getElementById("mesh-output");
  const weldInput = document.getElementById("mesh-weld");
  const limit = Number(form.dataset.limit) || Infinity;
  const PLOT_CONFIG = {
    displaylogo: false, responsive: true, displayModeBar: window.innerWidth < 600 ? false : "hover",
    modeBarButtonsToRemove: ["select2d", "lasso2d", "sendChartToCloud", "sendDataToCloud"],
    toImageButtonOptions: { format: "png", filename: "mesh-face-areas", scale: 2 },
  };
  form.classList.add("mesh-form-js");  // choosing or dropping a file starts at once
  let files = [];      // the files the page holds, sent again by every download
  let request = null;   // the upload in flight, if any

  function size(bytes) {
    if (bytes >= 1048576) return (bytes / 1048576).toFixed(1) + " MB";
    if (bytes >= 1024) return (bytes / 1024).toFixed(1) + " KB";
    return bytes + " bytes";
  }

  function say(text, kind) {
    status.textContent = text;
    status.className = "mesh-status" + (kind ? " message " + kind : "");
  }

  function showProgress(label, fraction) {
    progressRow.classList.remove("hidden");
    progressLabel.textContent = label;
    if (fraction === null) {
      progress.removeAttribute("value");  // indeterminate: the server is at work
      progressText.textContent = "";
    } else {
      progress.value = Math.round(fraction * 100);
      progressText.textContent = Math.round(fraction * 100) + "%";
    }
  }

  // An error answer may be our HTML fragment, the site's error page or the JSON of the
  // body limit; each carries one sentence.
  function errorSentence(xhr) {
    const type = xhr.getResponseHeader("content-type") || "";
    try {
      if (type.indexOf("json") !== -1) return JSON.parse(xhr.responseText).error;
      const doc = new DOMParser().parseFromString(xhr.responseText, "text/html");
      const message = doc.querySelector("[data-error], .message.error");
      if (message) return message.textContent.trim();
    } catch (error) { /* fall through to the generic sentence */ }
    return "The server could not read the file (status " + xhr.status + ").";
  }

  // "a.obj", "a.obj and a.mtl", "a.gltf, a.bin and b.bin"
  function listed(names) {
    if (names.length < 2) return names.join("");
    return names.slice(0, -1).join(", ") + " and " + names[names.length - 1];
  }

  function formData(chosen) {
    const body = new FormData();
    chosen.forEach(function (item) { body.append("file", item, item.name); });
    return body;
  }

  // `chosen`: one File, or a FileList or array of them (one mesh sent as several files).
  function upload(chosen) {
    const list = chosen instanceof File ? [chosen] : Array.prototype.slice.call(chosen || []);
    if (!list.length) { say("Choose a mesh file first.", "error"); input.focus(); return; }
    const names = listed(list.map(function (item) { return item.name; }));
    const total = list.reduce(function (sum, item) { return sum + item.size; }, 0);
    if (total > limit) {
      say(names + (list.length > 1 ? " are " : " is ") + size(total) +
          (list.length > 1 ? " together" : "") + ", larger than the limit of " +
          form.dataset.limitText + ".", "error");
      return;
    }
    if (weldInput && !weldInput.validity.valid) {
      say("The weld tolerance must be a number from 0 to " + weldInput.max + ", or empty.", "error");
      weldInput.focus();
      return;
    }
    if (request) request.abort();
    files = list;
    const body = formData(list);
    if (weldInput && weldInput.value !== "") body.append("weld", weldInput.value);
    const xhr = new XMLHttpRequest();
    request = xhr;
    xhr.open("POST", "/mesh?part=report");
    xhr.upload.onprogress = function (event) {
      if (event.lengthComputable) showProgress("Uploading", event.loaded / event.total);
    };
    xhr.upload.onload = function () {
      showProgress("Analysing", null);
      say("Analysing " + names + "…");
    };
    xhr.onload = function () {
      if (request !== xhr) return;
      request = null;
      progressRow.classList.add("hidden");
      if (xhr.status === 200) {
        render(xhr.responseText);
      } else {
        const sentence = errorSentence(xhr);
        const fragment = (xhr.getResponseHeader("content-type") || "").indexOf("html") !== -1 &&
          xhr.responseText.indexOf('id="mesh-error"') !== -1 &&
          xhr.responseText.indexOf("<html") === -1;
        if (fragment) output.innerHTML = xhr.responseText;
        say(sentence, "error");
        files = [];
      }
    };
    xhr.onerror = function () {
      if (request !== xhr) return;
      request = null;
      progressRow.classList.add("hidden");
      say("The upload of " + names + " failed; check the connection and try again.", "error");
    };
    showProgress("Uploading", 0);
    say("Uploading " + names + " (" + size(total) + ")…");
    xhr.send(body);
  }

  function data(id) {
    const element = document.getElementById(id);
    return element ? JSON.parse(element.textContent) : null;
  }

  function themedLayout(layout) {
    const dark = window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches;
    if (!dark) return layout;
    const copy = JSON.parse(JSON.stringify(layout));
    copy.font = Object.assign({}, copy.font, { color: "#c3cade" });
    return copy;
  }

  function drawHistogram() {
    const element = document.getElementById("mesh-histogram");
    const figure = data("mesh-histogram-data");
    if (!element || !figure || !window.Plotly) return Promise.resolve();
    return window.Plotly.react(element, figure.data, themedLayout(figure.layout), PLOT_CONFIG)
      .then(function () { element.dataset.drawn = String(Date.now()); });
  }

  // Controls that only work with this script are in the page hidden: without it, they would
  // be buttons that do nothing.
  function showScripted() {
    document.querySelectorAll("[data-needs-js]").forEach(function (element) { element.hidden = false; });
  }

  // Face orientation, as Blender shows it: the surface twice, each face moved a hair along its
  // own normal (blue) and against it (red). From outside, a mesh wound outward is blue and a
  // part wound inward (or a single face wound against its neighbours) is red.
  const FRONT = "#2f6fed";
  const BACK = "#e0312f";
  const ORIENTATION_OFFSET = 1e-3;  // of the view's diagonal: clear of depth fighting, too thin to see
  const PROBLEM_TRACES = ["faces", "boundary edges", "non-manifold edges", "degenerate"];

  function orientationTraces(surface) {
    const n = surface.i.length;
    const x = surface.x, y = surface.y, z = surface.z;
    let low = [Infinity, Infinity, Infinity], high = [-Infinity, -Infinity, -Infinity];
    for (let v = 0; v < x.length; v++) {
      const p = [x[v], y[v], z[v]];
      for (let a = 0; a < 3; a++) { low[a] = Math.min(low[a], p[a]); high[a] = Math.max(high[a], p[a]); }
    }
    const diagonal = Math.hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]) || 1;
    const offset = ORIENTATION_OFFSET * diagonal;
    const copies = [[], []].map(function () { return { x: [], y: [], z: [] }; });
    const corners = [surface.i, surface.j, surface.k];
    for (let f = 0; f < n; f++) {
      const p = corners.map(function (c) { return [x[c[f]], y[c[f]], z[c[f]]]; });
      const u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
      const w = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
      const normal = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
      const length = Math.hypot(normal[0], normal[1], normal[2]);
      const scale = length > 0 ? offset / length : 0;
      [1, -1].forEach(function (side, c) {
        for (let corner = 0; corner < 3; corner++) {
          copies[c].x.push(p[corner][0] + side * scale * normal[0]);
          copies[c].y.push(p[corner][1] + side * scale * normal[1]);
          copies[c].z.push(p[corner][2] + side * scale * normal[2]);
        }
      });
    }
    const index = [[], [], []];
    for (let f = 0; f < n; f++) { index[0].push(3 * f); index[1].push(3 * f + 1); index[2].push(3 * f + 2); }
    return [["front faces", FRONT], ["back faces", BACK]].map(function (named, c) {
      return {
        type: "mesh3d", name: named[0], x: copies[c].x, y: copies[c].y, z: copies[c].z,
        i: index[0], j: index[1], k: index[2], color: named[1], flatshading: true,
        hoverinfo: "skip", lighting: surface.lighting, lightposition: surface.lightposition,
        visible: false,
      };
    });
  }

  // Normals as arrows: the kind, how many and how long the user chose, from the pools the
  // report carries (a fair sample in a fixed order, so "how many" takes the first ones).
  const ARROW_NAMES = ["normals", "flipped normals"];
  const ARROW_COLOR = "#3a44b0";
  const FLIPPED_COLOR = "#f76707";

  function diagonalOf(trace) {
    const low = [Infinity, Infinity, Infinity], high = [-Infinity, -Infinity, -Infinity];
    [trace.x, trace.y, trace.z].forEach(function (values, a) {
      values.forEach(function (value) {
        if (value === null) return;
        low[a] = Math.min(low[a], value);
        high[a] = Math.max(high[a], value);
      });
    });
    return Math.hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]) || 1;
  }

  function arrowTraces(name, color, pool, rows, length, cone) {
    if (!rows.length) return [];
    const line = { x: [], y: [], z: [] }, tips = { x: [], y: [], z: [] }, heads = { u: [], v: [], w: [] };
    const head = 0.3 * length;
    rows.forEach(function (r) {
      const at = pool.at[r], n = pool.normal[r];
      ["x", "y", "z"].forEach(function (axis, a) {
        line[axis].push(at[a], at[a] + n[a] * (length - head), null);
        tips[axis].push(at[a] + n[a] * length);
      });
      heads.u.push(n[0] * head); heads.v.push(n[1] * head); heads.w.push(n[2] * head);
    });
    const hover = rows.map(function (r) {
      const n = pool.normal[r];
      return pool.label[r] + ": normal (" + n.map(function (c) { return Number(c.toPrecision(4)); }).join(", ") + ")";
    });
    return [
      { type: "scatter3d", mode: "lines", name: name, x: line.x, y: line.y, z: line.z,
        line: { color: color, width: 3 }, hoverinfo: "skip" },
      Object.assign({}, cone, {
        type: "cone", name: name, x: tips.x, y: tips.y, z: tips.z, u: heads.u, v: heads.v, w: heads.w,
        anchor: "tip", sizemode: "raw", sizeref: 1, colorscale: [[0, color], [1, color]],
        showscale: false, hovertext: hover, hovertemplate: "%{hovertext}<extra></extra>",
      }),
    ];
  }

  // The arrows the controls ask for, in place of the report's; null when the controls are
  // not on the page. Writes what is drawn into the caption.
  function chosenArrows(figure) {
    const pools = data("mesh-view-normals");
    const kind = document.getElementById("mesh-arrow-kind");
    const countInput = document.getElementById("mesh-arrow-count");
    const lengthInput = document.getElementById("mesh-arrow-length");
    if (!pools || !kind || !countInput || !lengthInput) return null;
    let pool = pools[kind.value] || pools.face;
    if (!pool) return null;
    const count = Math.max(0, Math.min(pool.at.length, Math.round(Number(countInput.value)) || 0));
    const angle = creaseAngle();
    const creased = pool.around && angle !== null;
    if (creased) {
      const cos = creaseCos(angle);
      pool = Object.assign({}, pool, { normal: pool.around.slice(0, count).map(function (around) { return creasedCorner(around, cos); }) });
    }
    const surface = figure.data.find(function (trace) { return trace.name === "faces"; });
    const length = Number(lengthInput.value) * (surface ? diagonalOf(surface) : 1);
    const cone = figure.data.find(function (trace) { return trace.type === "cone"; }) || {};
    const lighting = cone.lighting ? { lighting: cone.lighting } : {};
    const rows = [], flipped = [];
    for (let r = 0; r < count; r++) ((pool.flipped && pool.flipped[r]) ? flipped : rows).push(r);
    const caption = document.getElementById("mesh-view-arrows");
    const noun = { face: "faces", vertex: "vertices", corner: "corners" }[pools[kind.value] ? kind.value : "face"];
    if (caption) {
      caption.textContent = count ? " Arrows: the unit normals of " + count + " " + noun +
        (creased ? ", smooth by angle " + angle + "°" : "") + "." : " No arrows.";
    }
    return arrowTraces("normals", ARROW_COLOR, pool, rows, length, lighting)
      .concat(arrowTraces("flipped normals", FLIPPED_COLOR, pool, flipped, length, lighting));
  }

  // Smooth by angle, as Blender's: each corner of a vertex takes the faces at the vertex whose
  // normal is within the angle of its own face's (as mesh_normal.corner_normals does), and
  // corners that take the same faces share one copy of the vertex; the others get their own,
  // so Plotly's vertex normals (averaged over the faces sharing a vertex) show the creases.
  const CREASE_SLACK = 1e-6;  // the normals are rounded to 5 decimals
  const GREEDY_ABOVE = 64;    // a vertex with more corners groups them by the first of each

  function creaseAngle() {
    const slider = document.getElementById("mesh-crease");
    return slider ? Math.max(0, Math.min(180, Number(slider.value) || 0)) : null;
  }

  function creaseWords(angle) {
    if (angle >= 180) return "180°: every edge smooth";
    if (angle <= 0) return "0°: every face flat";
    return angle + "°: edges between faces more than " + angle + "° apart stay sharp";
  }

  function creaseCos(angle) { return Math.cos(angle * Math.PI / 180) - CREASE_SLACK; }

  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

  function creasedSurface(surface, normals, angle) {
    const m = surface.i.length, n = surface.x.length, index = [surface.i, surface.j, surface.k];
    if (!normals || normals.length !== m) return surface;
    const cos = creaseCos(angle);
    const start = new Int32Array(n + 1);
    for (let c = 0; c < 3; c++) for (let f = 0; f < m; f++) start[index[c][f] + 1]++;
    for (let v = 0; v < n; v++) start[v + 1] += start[v];
    const fill = start.slice(0, n), corners = new Int32Array(3 * m);
    for (let f = 0; f < m; f++) for (let c = 0; c < 3; c++) corners[fill[index[c][f]]++] = 3 * f + c;
    const x = [], y = [], z = [], out = [new Array(m), new Array(m), new Array(m)];
    for (let v = 0; v < n; v++) {
      const around = corners.subarray(start[v], start[v + 1]);
      const copies = new Map();
      const seeds = [];
      for (let a = 0; a < around.length; a++) {
        const own = normals[Math.floor(around[a] / 3)];
        let key;
        if (cos <= -1) key = "all";
        else if (around.length > GREEDY_ABOVE) {
          key = seeds.findIndex(function (seed) { return dot(own, normals[Math.floor(around[seed] / 3)]) >= cos; });
          if (key === -1) { key = seeds.length; seeds.push(a); }
        } else {
          const group = [];
          for (let b = 0; b < around.length; b++) {
            if (b === a || dot(own, normals[Math.floor(around[b] / 3)]) >= cos) group.push(b);
          }
          key = group.join(",");
        }
        if (!copies.has(key)) {
          copies.set(key, x.length);
          x.push(surface.x[v]); y.push(surface.y[v]); z.push(surface.z[v]);
        }
        out[around[a] % 3][Math.floor(around[a] / 3)] = copies.get(key);
      }
    }
    return Object.assign({}, surface, { x: x, y: y, z: z, i: out[0], j: out[1], k: out[2], flatshading: false });
  }

  // A sampled corner's normal at the slider's angle: the area-weighted normals of the faces at
  // its vertex (the report sends them, its own face first) within the angle of its own face's.
  function creasedCorner(around, cos) {
    const unit = function (a) { const l = Math.hypot(a[0], a[1], a[2]); return l ? [a[0] / l, a[1] / l, a[2] / l] : null; };
    const own = unit(around[0]);
    if (!own) return [0, 0, 0];
    const sum = [0, 0, 0];
    around.forEach(function (a) {
      const u = unit(a);
      if (u && dot(u, own) >= cos) { sum[0] += a[0]; sum[1] += a[1]; sum[2] += a[2]; }
    });
    return (unit(sum) || own).map(function (c) { return Math.round(c * 1e5) / 1e5; });
  }

  function viewMode() {
    const select = document.getElementById("mesh-mode");
    return select ? select.value : "problems";
  }

  // The problem place the view looks at (an index into the report's spots), or -1: the whole
  // mesh. A new report starts with the whole mesh.
  let spot = -1;

  // Looking at a problem place: from its outward side, a little above, close enough to see the
  // faces around it.
  function spotCamera(place, up) {
    const out = place.outward, c = place.center;
    const direction = [out.x + 0.35 * up.x, out.y + 0.35 * up.y, out.z + 0.35 * up.z];
    const length = Math.hypot(direction[0], direction[1], direction[2]) || 1;
    const d = place.distance / length;
    return {
      up: up, center: c,
      eye: { x: c.x + direction[0] * d, y: c.y + direction[1] * d, z: c.z + direction[2] * d },
    };
  }

  function syncSpot() {
    const spots = data("mesh-view-spots") || [];
    const row = document.getElementById("mesh-spot-controls");
    const whole = document.getElementById("mesh-whole");
    const words = document.getElementById("mesh-spot-text");
    if (row) row.hidden = !spots.length;
    if (whole) whole.hidden = spot < 0;
    if (words) {
      words.textContent = spot < 0 ? "" :
        "Problem place " + (spot + 1) + " of " + spots.length + ": face " +
        spots[spot].face.toLocaleString("en-US");
    }
  }

  // The camera for the chosen up axis (the report's figure carries the format's own) or the
  // problem place chosen, and the traces of the chosen colours shown, the others hidden.
  function viewFigure() {
    const figure = data("mesh-view-data");
    const cameras = data("mesh-view-cameras");
    const spots = data("mesh-view-spots") || [];
    const select = document.getElementById("mesh-up");
    const element = document.getElementById("mesh-view");
    if (!figure) return figure;
    if (cameras && select && cameras[select.value]) figure.layout.scene.camera = cameras[select.value];
    if (spot >= 0 && spots[spot]) {
      figure.layout.scene.camera = spotCamera(spots[spot], figure.layout.scene.camera.up);
    } else {
      figure.layout.scene.camera = window.NormalView3D.fitted(figure.layout.scene.camera, element, figure.layout.height);
    }
    // Rotating and zooming stay when the colours change; a new up axis or problem place starts
    // a new view.
    figure.layout.uirevision = (select ? select.value : "view") + " " + spot;
    const arrows = chosenArrows(figure);
    if (arrows) {
      figure.data = figure.data.filter(function (trace) { return ARROW_NAMES.indexOf(trace.name) === -1; })
        .concat(arrows);
    }
    let surface = figure.data.find(function (trace) { return trace.name === "faces"; });
    const angle = creaseAngle();
    if (surface && angle !== null) {
      const creased = creasedSurface(surface, data("mesh-view-face-normals"), angle);
      figure.data = figure.data.map(function (trace) { return trace === surface ? creased : trace; });
      surface = creased;
    }
    if (surface) figure.data = figure.data.concat(orientationTraces(surface));
    const orientation = viewMode() === "orientation";
    figure.data.forEach(function (trace) {
      if (PROBLEM_TRACES.indexOf(trace.name) !== -1) trace.visible = !orientation;
      if (trace.name === "front faces" || trace.name === "back faces") trace.visible = orientation;
    });
    return figure;
  }

  function syncMode() {
    const orientation = viewMode() === "orientation";
    const problems = document.getElementById("mesh-problem-legend");
    const faces = document.getElementById("mesh-orientation-legend");
    if (problems) problems.classList.toggle("hidden", orientation);
    if (faces) faces.classList.toggle("hidden", !orientation);
    const element = document.getElementById("mesh-view");
    if (element) element.dataset.mode = viewMode();
  }

  // The 3D bundle (557 KB gzipped) loads only when the view scrolls into sight.
  function drawView() {
    const element = document.getElementById("mesh-view");
    const figure = viewFigure();
    if (!element || !figure || !window.NormalView3D) return;
    if (!element.dataset.drawn && !element.firstChild) {
      const placeholder = document.createElement("p");
      placeholder.className = "chart-placeholder muted";
      placeholder.textContent = "The 3D view loads when it scrolls into sight.";
      element.appendChild(placeholder);
    }
    const observer = new IntersectionObserver(function (entries) {
      if (!entries.some(function (entry) { return entry.isIntersecting; })) return;
      observer.disconnect();
      window.NormalView3D.show(element, viewFigure());  // its camera fitted to the size it has now
    });
    observer.observe(element);
  }

  function drawFigures() {
    showScripted();
    spot = -1;
    syncSpot();
    syncMode();
    drawView();
    return drawHistogram();
  }

  // The curl command comes with a relative address when the server has no MESH_PUBLIC_URL (it
  // never builds links from the Host header): this page's own address goes in front.
  function completeCurl() {
    const curl = document.getElementById("mesh-curl");
    const code = curl && (curl.querySelector("code") || curl);
    if (code) code.textContent = code.textContent.replace(/ \/api\//, " " + location.origin + "/api/");
  }

  function render(html) {
    output.innerHTML = html;
    completeCurl();
    const report = data("mesh-report");
    const items = report ? report.problems : [];
    const count = items.filter(function (item) { return item.severity !== "info"; }).length;
    const notes = items.length - count;
    const found = count ? count + (count === 1 ? " problem" : " problems") + " found" : "no problems found";
    say("Report ready for " + (report && report.file.name || "the file") + ": " + found +
        (notes ? (count ? " and " : ", ") + notes + (notes === 1 ? " note." : " notes.") : "."),
        "ok");
    const heading = document.getElementById("mesh-report-title");
    if (heading) heading.focus({ preventScroll: window.innerWidth >= 900 });
    syncFields();
    drawFigures();
  }

  // --- Downloads: the same file, sent again to the JSON API ---------------------------------

  function downloadStatus(text, kind) { Downloads.status("mesh-download-status", text, kind); }

  function save(blob, name) { Downloads.save(blob, name); }

  function filename(response, fallback) { return Downloads.filename(response, fallback); }

  function fetchDownload(path, params, fallback, button, fields) {
    if (!files.length && input.files.length) files = Array.prototype.slice.call(input.files);
    if (!files.length) {
      downloadStatus("Choose the file again: the page no longer holds it.", "error");
      return Promise.resolve();
    }
    const body = formData(files);
    Object.keys(fields || {}).forEach(function (key) { body.append(key, fields[key]); });
    if (button) button.disabled = true;
    downloadStatus("Preparing " + fallback + "…", "");
    return fetch(path + "?" + new URLSearchParams(params).toString(), { method: "POST", body: body })
      .then(function (response) {
        if (!response.ok) {
          return response.json().then(function (answer) {
            const field = answer.field ? " (" + answer.field + ")" : "";
            downloadStatus(answer.error + field, "error");
          }, function () {
            downloadStatus("The download failed (status " + response.status + ").", "error");
          });
        }
        const name = filename(response, fallback);
        // The fix names what the chosen format could not hold; never leave that unsaid.
        const dropped = response.headers.get("x-dropped");
        return response.blob().then(function (blob) {
          save(blob, name);
          if (dropped) downloadStatus("Saved " + name + ", which leaves out " + dropped + ".", "warn");
          else downloadStatus("Saved " + name + ".", "ok");
        });
      })
      .catch(function () { downloadStatus("The download failed; check the connection.", "error"); })
      .finally(function () { if (button) button.disabled = false; });
  }

  function downloadNormals(button) {
    const params = {
      kind: document.getElementById("normals-kind").value,
      weighting: document.getElementById("normals-weighting").value,
      crease_angle: document.getElementById("normals-crease").value,
      format: document.getElementById("normals-format").value,
    };
    const crease = Number(params.crease_angle);
    if (params.kind === "corner" && !(params.crease_angle !== "" && crease >= 0 && crease <= 180)) {
      downloadStatus("The crease angle must be a number of degrees from 0 to 180.", "error");
      document.getElementById("normals-crease").focus();
      return Promise.resolve();
    }
    if (params.kind !== "corner") delete params.crease_angle;
    if (params.kind === "face") delete params.weighting;
    return fetchDownload("/api/mesh/normals", params,
                         params.kind + "-normals." + params.format, button);
  }

  function downloadFix(button) {
    const format = document.getElementById("fix-format").value;
    // The weld the report was made with, so that the file is the fix the report describes.
    const view = document.getElementById("mesh-report-view");
    const fields = view && view.dataset.weld ? { weld: view.dataset.weld } : {};
    return fetchDownload("/api/mesh/fix", { format: format }, "fixed." + format, button, fields);
  }

  function downloadReport() {
    const element = document.getElementById("mesh-report");
    const view = document.getElementById("mesh-report-view");
    if (!element) return;
    const stem = view ? view.dataset.stem : "mesh";
    save(new Blob([element.textContent], { type: "application/json" }), stem + "-report.json");
  }

  // Before the fixed mesh is downloaded: what its chosen format leaves out of this mesh.
  function syncDropped() {
    const select = document.getElementById("fix-format");
    const slot = document.getElementById("fix-dropped");
    const sentences = data("mesh-fix-dropped");
    if (!select || !slot || !sentences) return;
    slot.textContent = sentences[select.value] || "";
    slot.classList.toggle("hidden", !slot.textContent);
  }

  // Weighting means nothing for face normals, the crease angle only for corner normals.
  function syncFields() {
    syncDropped();
    const kind = document.getElementById("normals-kind");
    if (!kind) return;
    document.getElementById("normals-weighting").disabled = kind.value === "face";
    document.getElementById("normals-crease").disabled = kind.value !== "corner";
  }

  function copy(button) {
    const source = document.getElementById(button.dataset.copy);
    if (!source || !navigator.clipboard || !window.isSecureContext) return;
    const label = button.textContent;
    navigator.clipboard.writeText(source.textContent).then(function () {
      button.textContent = "Copied";
      setTimeout(function () { button.textContent = label; }, 1500);
    }, function () {});
  }

  // --- Wiring -------------------------------------------------------------------------------

  input.addEventListener("change", function () { upload(input.files); });
  form.addEventListener("submit", function (event) {
    event.preventDefault();
    upload(input.files);
  });

  function hasFiles(event) {
    return event.dataTransfer && Array.prototype.indexOf.call(event.dataTransfer.types || [], "Files") !== -1;
  }
  ["dragenter", "dragover"].forEach(function (type) {
    dropzone.addEventListener(type, function (event) {
      event.preventDefault();
      dropzone.classList.add("dragging");
    });
  });
  ["dragleave", "dragend"].forEach(function (type) {
    dropzone.addEventListener(type, function () { dropzone.classList.remove("dragging"); });
  });
  dropzone.addEventListener("drop", function (event) {
    event.preventDefault();
    dropzone.classList.remove("dragging");
    const dropped = event.dataTransfer && event.dataTransfer.files;
    if (!dropped || !dropped.length) return;
    try { input.files = dropped; } catch (error) { /* older browsers: the page still holds them */ }
    upload(dropped);
  });
  // A file dropped beside the zone must not replace the page with the file itself.
  ["dragover", "drop"].forEach(function (type) {
    document.addEventListener(type, function (event) {
      if (hasFiles(event) && !dropzone.contains(event.target)) event.preventDefault();
    });
  });

  document.addEventListener("submit", function (event) {
    const which = event.target.dataset && event.target.dataset.meshForm;
    if (!which) return;
    event.preventDefault();
    const button = event.target.querySelector("button[type=submit]");
    if (which === "normals") downloadNormals(button);
    else downloadFix(button);
  });
  document.addEventListener("click", function (event) {
    const copyButton = event.target.closest("button[data-copy]");
    if (copyButton) { copy(copyButton); return; }
    if (event.target.closest("#mesh-report-download")) { downloadReport(); return; }
    const fixButton = event.target.closest("button[data-mesh-download=fix]");
    if (fixButton && !fixButton.closest("form")) downloadFix(fixButton);
    const next = event.target.closest("#mesh-next-problem");
    if (next || event.target.closest("#mesh-whole")) {
      const spots = data("mesh-view-spots") || [];
      spot = next && spots.length ? (spot + 1) % spots.length : -1;
      syncSpot();
      const element = document.getElementById("mesh-view");
      if (element && window.NormalView3D) window.NormalView3D.update(element, viewFigure());
    }
  });
  document.addEventListener("change", function (event) {
    if (event.target.id === "normals-kind") syncFields();
    if (event.target.id === "fix-format") syncDropped();
    if (event.target.id === "mesh-mode") syncMode();
    if (["mesh-up", "mesh-mode", "mesh-arrow-kind", "mesh-arrow-count", "mesh-arrow-length"]
        .indexOf(event.target.id) !== -1) {
      const element = document.getElementById("mesh-view");
      if (element && window.NormalView3D) window.NormalView3D.update(element, viewFigure());
    }
  });
  // The smoothing angle redraws as the slider moves, at most once a frame.
  let creaseFrame = 0;
  document.addEventListener("input", function (event) {
    if (event.target.id !== "mesh-crease") return;
    const words = document.getElementById("mesh-crease-text");
    if (words) words.textContent = creaseWords(creaseAngle());
    if (creaseFrame) return;
    creaseFrame = requestAnimationFrame(function () {
      creaseFrame = 0;
      const element = document.getElementById("mesh-view");
      if (element && window.NormalView3D) window.NormalView3D.update(element, viewFigure());
    });
  });
  // A new weld tolerance analyses the file the page holds again.
  if (weldInput) weldInput.addEventListener("change", function () { if (files.length) upload(files); });

  // A report the server rendered (the form posted without this script) is drawn too.
  if (document.getElementById("mesh-report")) { completeCurl(); syncFields(); drawFigures(); }
  window.meshUpload = upload;  // lets browser tests hand the page files directly
})();
