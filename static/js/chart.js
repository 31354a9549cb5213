// Draws the Plotly figure that the page carries as JSON. Shared by the calculator and /embed.
"use strict";

window.NormalChart = (function () {
  const CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["select2d", "lasso2d"] };

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
