// Saving an API answer as a file, for the mesh and point-cloud pages (mesh.js, mesh_tools.js,
// points.js): a status line under the buttons, the save itself, the server's file name.
"use strict";

window.Downloads = (function () {
  function status(slotId, text, kind) {
    const slot = document.getElementById(slotId);
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
    const header = response.headers.get("content-disposition") || "";
    const match = /filename="([^"]+)"/.exec(header);
    return match ? match[1] : fallback;
  }

  return { status: status, save: save, filename: filename };
})();
