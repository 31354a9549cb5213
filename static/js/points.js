// The point-cloud page. Without JavaScript the form posts the file and its options and the
// server answers with the whole page. With it, choosing or dropping a file uploads it at once
// with a progress bar (POST /points?part=report answers with the report alone), the figures
// are drawn from the report's JSON blocks, the view's controls swap the points' colouring, the
// up axis (and with it the camera and the light) and the normal strokes, and the downloads
// send the file the page still holds to POST /api/points/normals.
"use strict";

(function () {
  const form = document.getElementById("points-form");
  const input = document.getElementById("points-file");
  const dropzone = document.getElementById("points-dropzone");
  const progressRow = document.getElementById("points-progress-row");
  const progress = document.getElementById("points-progress");
  const progressLabel = document.getElementById("points-progress-label");
  const progressText = document.getElementById("points-progress-text");
  const status = document.getElementById("points-status");
  const output = document.getElementById("points-output");
  const limit = Number(form.dataset.limit) || Infinity;
  const FIELDS = ["k", "radius", "orient", "viewpoint", "direction"];
  const PLOT_CONFIG = {
    displaylogo: false, responsive: true, displayModeBar: window.innerWidth < 600 ? false : "hover",
    modeBarButtonsToRemove: ["select2d", "lasso2d", "sendChartToCloud", "sendDataToCloud"],
    toImageButtonOptions: { format: "png", filename: "points-histogram", scale: 2 },
  };
  form.classList.add("mesh-form-js");  // choosing or dropping a file starts at once
  let file = null;      // the file the page holds, sent again by every download
  let request = null;   // the upload in flight, if any
  let view = null;      // the 3D view's figure, its colourings and its cameras

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

  // An error answer may be our HTML fragment, the site's error page or JSON; each carries
  // one sentence.
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

  // The form's options, as the page's form sends them.
  function fields() {
    const values = {};
    FIELDS.forEach(function (name) {
      const element = form.elements.namedItem(name);
      if (element && element.value.trim() !== "") values[name] = element.value.trim();
    });
    return values;
  }

  function upload(chosen) {
    const item = chosen instanceof File ? chosen : (chosen && chosen[0]);
    if (!item) { say("Choose a point-cloud file first.", "error"); input.focus(); return; }
    if (item.size > limit) {
      say(item.name + " is " + size(item.size) + ", larger than the limit of " +
          form.dataset.limitText + ".", "error");
      return;
    }
    if (request) request.abort();
    file = item;
    const body = new FormData();
    body.append("file", item, item.name);
    const values = fields();
    Object.keys(values).forEach(function (key) { body.append(key, values[key]); });
    const xhr = new XMLHttpRequest();
    request = xhr;
    xhr.open("POST", "/points?part=report");
    xhr.upload.onprogress = function (event) {
      if (event.lengthComputable) showProgress("Uploading", event.loaded / event.total);
    };
    xhr.upload.onload = function () {
      showProgress("Analysing", null);
      say("Estimating the normals of " + item.name + "…");
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
          xhr.responseText.indexOf('id="points-error"') !== -1 &&
          xhr.responseText.indexOf("<html") === -1;
        if (fragment) output.innerHTML = xhr.responseText;
        say(sentence, "error");
        file = null;
      }
    };
    xhr.onerror = function () {
      if (request !== xhr) return;
      request = null;
      progressRow.classList.add("hidden");
      say("The upload of " + item.name + " failed; check the connection and try again.", "error");
    };
    showProgress("Uploading", 0);
    say("Uploading " + item.name + " (" + size(item.size) + ")…");
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
    const element = document.getElementById("points-histogram");
    const figure = data("points-histogram-data");
    if (!element || !figure || !window.Plotly) return Promise.resolve();
    return window.Plotly.react(element, figure.data, themedLayout(figure.layout), PLOT_CONFIG)
      .then(function () { element.dataset.drawn = String(Date.now()); });
  }

  // The figure as the controls ask: the points coloured by the chosen scheme (the light's
  // shading for the chosen up axis, or curvature), the strokes shown or not, and the camera
  // for the chosen up axis, fitted to the canvas. Recolouring keeps the reader's rotation
  // (the same uirevision); a new up axis starts from its own camera.
  function viewFigure() {
    const element = document.getElementById("points-view");
    const select = document.getElementById("points-up");
    const strokes = document.getElementById("points-strokes");
    const up = select && view.cameras[select.value] ? select.value : view.up;
    const scheme = element ? element.dataset.color : "light";
    const marker = scheme === "curvature" ? view.colors.curvature : view.colors.light[up];
    const traces = view.figure.data.map(function (trace, index) {
      if (index === 0) return Object.assign({}, trace, { marker: marker });
      return Object.assign({}, trace, { visible: strokes ? strokes.checked : true });
    });
    const layout = JSON.parse(JSON.stringify(view.figure.layout));
    layout.scene.camera = window.NormalView3D.fitted(view.cameras[up], element, layout.height);
    layout.uirevision = up;
    return { data: traces, layout: layout };
  }

  function showScripted() {
    document.querySelectorAll("#points-report-view [data-needs-js]").forEach(function (element) {
      element.hidden = false;
    });
  }

  // The 3D bundle loads only when the view scrolls into sight.
  function drawView() {
    const element = document.getElementById("points-view");
    view = data("points-view-data");
    if (!element || !view || !window.NormalView3D) return;
    showScripted();
    element.dataset.color = "light";
    const observer = new IntersectionObserver(function (entries) {
      if (!entries.some(function (entry) { return entry.isIntersecting; })) return;
      observer.disconnect();
      window.NormalView3D.show(element, viewFigure());  // its camera fitted to the size it has now
    });
    observer.observe(element);
  }

  function redraw() {
    const element = document.getElementById("points-view");
    if (element && view) window.NormalView3D.update(element, viewFigure());
  }

  function recolor(button) {
    const element = document.getElementById("points-view");
    if (!element || !view) return;
    element.dataset.color = button.dataset.pointsColor;
    document.querySelectorAll("button[data-points-color]").forEach(function (other) {
      other.setAttribute("aria-pressed", String(other === button));
    });
    redraw();
  }

  function completeCurl() {
    const curl = document.getElementById("points-curl");
    const code = curl && (curl.querySelector("code") || curl);
    if (code) code.textContent = code.textContent.replace(/ '?\/api\//, function (found) {
      return found.replace("/api/", location.origin + "/api/");
    });
  }

  function render(html) {
    output.innerHTML = html;
    completeCurl();
    const report = data("points-report");
    const missing = report ? report.points - report.with_normal : 0;
    // The status line reads as the diagnosis does: a warning is not a success.
    const diagnosis = document.getElementById("points-diagnosis");
    const verdict = diagnosis ? diagnosis.dataset.verdict : "ok";
    say("Report ready for " + (report && report.file.name || "the file") + ": " +
        (report ? report.with_normal.toLocaleString() + " of " + report.points.toLocaleString() +
         " points have a normal" : "done") + (missing ? "." : ", every one.") +
        (verdict === "ok" ? "" : " See the diagnosis."), verdict || "ok");
    const heading = document.getElementById("points-report-title");
    if (heading) heading.focus({ preventScroll: window.innerWidth >= 900 });
    drawView();
    drawHistogram();
  }

  // --- Downloads: the same file, sent again to the JSON API ---------------------------------

  function downloadStatus(text, kind) { Downloads.status("points-download-status", text, kind); }

  function save(blob, name) { Downloads.save(blob, name); }

  function filename(response, fallback) { return Downloads.filename(response, fallback); }

  function download(button) {
    if (!file && input.files.length) file = input.files[0];
    if (!file) {
      downloadStatus("Choose the file again: the page no longer holds it.", "error");
      return Promise.resolve();
    }
    const format = button.dataset.pointsDownload;
    const report = document.getElementById("points-report-view");
    const params = new URLSearchParams(report ? report.dataset.query : "");
    params.set("format", format);
    const body = new FormData();
    body.append("file", file, file.name);
    button.disabled = true;
    downloadStatus("Preparing the normals as " + format.toUpperCase() + "…", "");
    return fetch("/api/points/normals?" + params.toString(), { method: "POST", body: body })
      .then(function (response) {
        if (!response.ok) {
          return response.json().then(function (answer) {
            downloadStatus(answer.error, "error");
          }, function () {
            downloadStatus("The download failed (status " + response.status + ").", "error");
          });
        }
        const name = filename(response, "normals." + format);
        const missing = Number(response.headers.get("x-points-without-normal") || 0);
        return response.blob().then(function (blob) {
          save(blob, name);
          downloadStatus("Saved " + name + (missing ? "; " + missing.toLocaleString() +
            (missing === 1 ? " point has" : " points have") + " no normal (zeros)." : "."), missing ? "warn" : "ok");
        });
      })
      .catch(function () { downloadStatus("The download failed; check the connection.", "error"); })
      .finally(function () { button.disabled = false; });
  }

  function downloadReport() {
    const element = document.getElementById("points-report");
    if (!element) return;
    const report = JSON.parse(element.textContent);
    const stem = ((report.file.name || "points").replace(/\.[^.]*$/, "")
      .replace(/[^A-Za-z0-9_-]+/g, "-") || "points");
    save(new Blob([element.textContent], { type: "application/json" }), stem + "-report.json");
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
    try { input.files = dropped; } catch (error) { /* older browsers: the page still holds it */ }
    upload(dropped);
  });
  ["dragover", "drop"].forEach(function (type) {
    document.addEventListener(type, function (event) {
      if (hasFiles(event) && !dropzone.contains(event.target)) event.preventDefault();
    });
  });

  document.addEventListener("click", function (event) {
    const copyButton = event.target.closest("button[data-copy]");
    if (copyButton) { copy(copyButton); return; }
    if (event.target.closest("#points-report-download")) { downloadReport(); return; }
    const colorButton = event.target.closest("button[data-points-color]");
    if (colorButton) { recolor(colorButton); return; }
    const downloadButton = event.target.closest("button[data-points-download]");
    if (downloadButton) download(downloadButton);
  });
  // New options analyse the file the page holds again; the direction mode waits for its
  // direction rather than answer with an error at once.
  // The view's own controls redraw it; they are not the form's options.
  document.addEventListener("change", function (event) {
    if (event.target.id === "points-up" || event.target.id === "points-strokes") redraw();
  });
  form.addEventListener("change", function (event) {
    if (event.target === input || !file || !(event.target.validity && event.target.validity.valid)) return;
    const values = fields();
    if (values.orient === "direction" && !values.direction) {
      say("Give the direction x,y,z, e.g. 0,0,1, to orient along it.", "");
      return;
    }
    upload(file);
  });

  // A report the server rendered (the form posted without this script) is drawn too.
  if (document.getElementById("points-report")) { completeCurl(); drawView(); drawHistogram(); }
  window.pointsUpload = upload;  // lets browser tests hand the page files directly
})();
