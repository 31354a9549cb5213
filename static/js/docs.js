// Starts Swagger UI from our own files; kept out of the HTML so the CSP needs no inline script.
"use strict";

// Swagger UI has a dark mode of its own, switched by a class on <html>: follow the reader's
// colour scheme, also when it changes while the page is open.
(function () {
  const dark = window.matchMedia("(prefers-color-scheme: dark)");
  function follow() { document.documentElement.classList.toggle("dark-mode", dark.matches); }
  follow();
  dark.addEventListener("change", follow);
})();

window.addEventListener("DOMContentLoaded", function () {
  const root = document.getElementById("swagger-ui");
  window.ui = window.SwaggerUIBundle({
    url: root.dataset.openapiUrl,
    dom_id: "#swagger-ui",
    deepLinking: true,
    tryItOutEnabled: true,
    presets: [window.SwaggerUIBundle.presets.apis],
    layout: "BaseLayout",
  });
});
