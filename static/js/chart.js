// Draws the Plotly figure that the page carries as JSON. Shared by the calculator and /embed.
"use strict";

window.NormalChart = (function () {
  const CONFIG = {
    displaylogo: false, responsive: true,
    // On a phone the toolbar would cover the title; it is for desktop use.
    displayModeBar: window.innerWidth < 600 ? false : "hover",
    modeBarButtonsToRemove: ["select2d", "lasso2d"],
  };

  function themed(layout) {
    const dark = window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches;
    if (!dark) return layout;
    const copy = JSON.parse(JSON.stringify(layout));
    copy.font = Object.assign({}, copy.font, { color: "#c3cade" });
    copy.yaxis = Object.assign({}, copy.yaxis, { gridcolor: "#2f3850", zerolinecolor: "#69728a" });
    return copy;
  }

  function draw(element, figure) {
    if (!figure || !window.Plotly) return Promise.resolve();
    const placeholder = element.querySelector(".chart-placeholder");
    if (placeholder) placeholder.remove();
    return window.Plotly.react(element, figure.data, themed(figure.layout), CONFIG).then(function () {
      element.dataset.drawn = String(Date.now());
      if (!window.__chartDrawnAt) {
        window.__chartDrawnAt = performance.now();
        performance.mark("chart-drawn");
      }
    });
  }

  function drawFromPage() {
    const element = document.getElementById("chart");
    const data = document.getElementById("figure-data");
    if (!element || !data) return Promise.resolve();
    return draw(element, JSON.parse(data.textContent));
  }

  return { draw: draw, drawFromPage: drawFromPage };
})();
