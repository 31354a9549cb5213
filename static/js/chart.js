// Draws the Plotly figure that the page carries as JSON. Shared by the calculator and /embed.
"use strict";

window.NormalChart = (function () {
  // On a phone the toolbar would cover the title; it is for desktop use.
  const TOOLBAR = window.innerWidth < 600 ? false : "hover";
  const CONFIG = {
    displaylogo: false, responsive: true, displayModeBar: TOOLBAR,
    // "Share chart" would post the data to an outside service: this page keeps it here.
    modeBarButtonsToRemove: ["select2d", "lasso2d", "sendChartToCloud", "sendDataToCloud"],
    toImageButtonOptions: { format: "png", filename: "triangle-normal", scale: 2 },
    modeBarButtonsToAdd: [{
      name: "downloadSvg",
      title: "Download plot as SVG",
      icon: { width: 1000, height: 1000, path: "M500 50 L500 650 M280 430 L500 650 L720 430 M150 800 L850 800 L850 950 L150 950 Z", transform: "matrix(1 0 0 1 0 0)" },
      click: function (gd) {
        window.Plotly.downloadImage(gd, { format: "svg", filename: "triangle-normal" });
      },
    }],
  };
  // The first draw leaves the toolbar out (building it costs about a tenth of a second on a
  // slow machine) and adds it once the page is idle, so the chart shows sooner.
  const FIRST = Object.assign({}, CONFIG, { displayModeBar: false });

  // The embed's ?theme= fixes the colours with a class on the body; otherwise the reader's
  // colour scheme decides.
  function isDark() {
    const body = document.body.classList;
    if (body.contains("theme-dark") || body.contains("theme-light")) return body.contains("theme-dark");
    return Boolean(window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches);
  }

  function themed(layout) {
    if (!isDark()) return layout;
    const copy = JSON.parse(JSON.stringify(layout));
    copy.font = Object.assign({}, copy.font, { color: "#c3cade" });
    copy.xaxis = Object.assign({}, copy.xaxis, { gridcolor: "#2f3850", zerolinecolor: "#69728a" });
    copy.yaxis = Object.assign({}, copy.yaxis, { gridcolor: "#2f3850", zerolinecolor: "#69728a" });
    return copy;
  }

  // Bar labels follow the calculator's precision setting (/embed has none and keeps the
  // server's text): each bar carries its number in full as customdata.
  function labelled(data) {
    const precision = document.getElementById("precision");
    if (!precision || !window.NumberText) return data;
    return data.map(function (trace) {
      if (!trace.customdata) return trace;
      const text = trace.customdata.map(function (number, i) {
        return number === null ? trace.text[i] : window.NumberText.format(number, precision.value);
      });
      return Object.assign({}, trace, { text: text });
    });
  }

  function whenIdle(callback) {
    if (window.requestIdleCallback) window.requestIdleCallback(callback, { timeout: 1000 });
    else setTimeout(callback, 200);
  }

  function draw(element, figure) {
    if (!figure || !window.Plotly) return Promise.resolve();
    const placeholder = element.querySelector(".chart-placeholder");
    if (placeholder) placeholder.remove();
    const first = !element.dataset.drawn;
    const config = first && TOOLBAR ? FIRST : CONFIG;
    element.figure = figure;  // kept to redraw the labels when the precision changes
    return window.Plotly.react(element, labelled(figure.data), themed(figure.layout), config).then(function () {
      element.dataset.drawn = String(Date.now());
      if (!window.__chartDrawnAt) {
        window.__chartDrawnAt = performance.now();
        performance.mark("chart-drawn");
      }
      if (config === FIRST) {
        whenIdle(function () {
          window.Plotly.react(element, element.data, element.layout, CONFIG);
        });
      }
    });
  }

  function drawFromPage() {
    const element = document.getElementById("chart");
    const data = document.getElementById("figure-data");
    if (!element || !data) return Promise.resolve();
    return draw(element, JSON.parse(data.textContent));
  }

  document.addEventListener("change", function (event) {
    const element = document.getElementById("chart");
    if (event.target.id !== "precision" || !element || !element.figure) return;
    window.Plotly.react(element, labelled(element.figure.data), element.layout, CONFIG);
  });

  return { draw: draw, drawFromPage: drawFromPage };
})();
