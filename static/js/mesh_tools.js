// The mesh report's tools beside mesh.js: "Download with normals" (optionally with every face
// flipped) sends the file the page holds to POST /api/mesh/export and saves the answer. The
// server keeps nothing, so without this script the form cannot send the file again and stays
// hidden (data-needs-js). On a sample's page the page holds no file yet: the sample's own file
// is fetched and put in the file field, so that every download of the page has it to send.
"use strict";

(function () {
  const input = document.getElementById("mesh-file");
  if (!input) return;

  function status(text, kind) {
    const slot = document.getElementById("mesh-download-status");
    if (!slot) return;
    slot.textContent = text;
    slot.className = "message small" + (kind ? " " + kind : "") + (text ? "" : " hidden");
  }

  function save(blob, name) {
    const url = URL.createObjectURL(blob);
    const link = document.createElement("a");
    link.href = url;
    link.download = name;
    document.body.appendChild(link);
    link.click();
    link.remove();
    setTimeout(function () { URL.revokeObjectURL(url); }, 10000);
  }

  function filename(response, fallback) {
    const match = /filename="([^"]+)"/.exec(response.headers.get("content-disposition") || "");
    return match ? match[1] : fallback;
  }

  // The sample of this report, fetched once and kept as a File in the file field.
  let sampleFile = null;
  function loadSample() {
    const view = document.getElementById("mesh-report-view");
    const name = view && view.dataset.sample;
    if (!name || input.files.length) return Promise.resolve(null);
    if (sampleFile && sampleFile.sample === name) return sampleFile.promise;
    const promise = fetch("/mesh/sample/" + encodeURIComponent(name) + "/file")
      .then(function (response) {
        if (!response.ok) throw new Error("status " + response.status);
        return response.blob().then(function (blob) {
          const file = new File([blob], filename(response, name), { type: blob.type });
          try {
            const transfer = new DataTransfer();
            transfer.items.add(file);
            input.files = transfer.files;  // no change event: the report stays as it is
          } catch (error) { /* older browsers: this script still holds the file */ }
          return file;
        });
      });
    sampleFile = { sample: name, promise: promise };
    return promise;
  }

  function chosenFiles() {
    if (input.files.length) return Promise.resolve(Array.prototype.slice.call(input.files));
    return loadSample().then(function (file) { return file ? [file] : []; });
  }

  function exportMesh(form) {
    const button = form.querySelector("button[type=submit]");
    const params = new URLSearchParams({
      format: form.elements.format.value,
      normals: form.elements.normals.value,
      winding: form.elements.flip.checked ? "flip" : "keep",
    });
    // Corner normals as the 3D view previews them: at its Smooth by angle slider's angle.
    const crease = document.getElementById("mesh-crease");
    if (crease && ["corner", "auto"].indexOf(params.get("normals")) !== -1) {
      params.set("crease_angle", crease.value);
    }
    const fallback = "mesh-export." + params.get("format");
    if (button) button.disabled = true;
    status("Preparing " + fallback + "…", "");
    return chosenFiles()
      .then(function (files) {
        if (!files.length) {
          status("Choose the file again: the page no longer holds it.", "error");
          return null;
        }
        const body = new FormData();
        files.forEach(function (file) { body.append("file", file, file.name); });
        return fetch("/api/mesh/export?" + params.toString(), { method: "POST", body: body })
          .then(function (response) {
            if (!response.ok) {
              return response.json().then(function (answer) {
                status(answer.error + (answer.field ? " (" + answer.field + ")" : ""), "error");
              }, function () {
                status("The download failed (status " + response.status + ").", "error");
              });
            }
            const name = filename(response, fallback);
            const dropped = response.headers.get("x-dropped");
            const flipped = Number(response.headers.get("x-faces-flipped") || 0);
            return response.blob().then(function (blob) {
              save(blob, name);
              const what = "Saved " + name + " with " + (response.headers.get("x-normals") || "no") +
                " normals" + (flipped ? ", " + flipped.toLocaleString("en") + " faces flipped" : "");
              if (dropped) status(what + "; it leaves out " + dropped + ".", "warn");
              else status(what + ".", "ok");
            });
          });
      })
      .catch(function () { status("The download failed; check the connection.", "error"); })
      .finally(function () { if (button) button.disabled = false; });
  }

  document.addEventListener("submit", function (event) {
    const form = event.target;
    if (!form.dataset || form.dataset.meshTools !== "export") return;
    event.preventDefault();
    exportMesh(form);
  });

  // Beside the export's choice of corner normals: the angle they will be smoothed by.
  function syncCrease() {
    const slot = document.getElementById("export-crease");
    const select = document.getElementById("export-normals");
    const crease = document.getElementById("mesh-crease");
    if (!slot || !select || !crease) return;
    slot.textContent = "at " + crease.value + "°, the 3D view's smoothing angle";
    slot.classList.toggle("hidden", select.value !== "corner");
  }
  ["input", "change"].forEach(function (type) {
    document.addEventListener(type, function (event) {
      if (event.target.id === "mesh-crease" || event.target.id === "export-normals") syncCrease();
    });
  });

  // A sample's page: fetch its file now, so that the page's other downloads have it too.
  loadSample().catch(function () { /* the export says so when it is asked for */ });
  window.meshTools = { exportMesh: exportMesh, loadSample: loadSample };  // for browser tests
})();
