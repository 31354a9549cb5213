// The 3D view of the triangle and its normal. The gl3d bundle of Plotly.js is large, so it is
// loaded the first time the view is shown, from the URL in the element's data-src. It sets
// window.Plotly when it runs; this puts back the page's own instance (the basic bundle that
// draws the bar chart) and keeps the gl3d one to itself.
"use strict";

window.NormalView3D = (function () {
  // "Share chart" would post the data to an outside service: this page keeps it here.
  const CONFIG = {
    displaylogo: false, responsive: true,
    modeBarButtonsToRemove: ["sendChartToCloud", "sendDataToCloud"],
    toImageButtonOptions: { format: "png", filename: "triangle-3d", scale: 2 },
  };
  let plotly = null;
  let loading = null;
  let webgl = null;
  const shown = new WeakSet();
  const waiting = new WeakMap();  // figures given to update() before the first show()
  const queues = new WeakMap();   // one draw at a time per element

  function hasWebGL() {
    if (webgl === null) {
      try {
        const context = document.createElement("canvas").getContext("webgl");
        webgl = Boolean(context);
        const lose = context && context.getExtension("WEBGL_lose_context");
        if (lose) lose.loseContext();
      } catch (error) {
        webgl = false;
      }
    }
    return webgl;
  }

  function load(src) {
    if (loading) return loading;
    loading = new Promise(function (resolve, reject) {
      const had = Object.prototype.hasOwnProperty.call(window, "Plotly");
      const basic = window.Plotly;
      const script = document.createElement("script");
      script.src = src;
      script.async = true;
      // The script runs and its load event fires in one task: nothing sees the swap.
      script.onload = function () {
        const gl3d = window.Plotly;
        if (had) window.Plotly = basic;
        else delete window.Plotly;
        if (!gl3d || gl3d === basic) { loading = null; reject(new Error("no gl3d Plotly")); return; }
        plotly = gl3d;
        resolve(gl3d);
      };
      script.onerror = function () {
        loading = null;
        script.remove();
        reject(new Error("the 3D view's script did not load"));
      };
      document.head.appendChild(script);
    });
    return loading;
  }

  function say(element, text) {
    element.textContent = "";
    const note = document.createElement("p");
    note.className = "chart-placeholder muted";
    note.textContent = text;
    element.appendChild(note);
  }

  // Dark mode: the figure's colours, lightened to read on the dark card.
  const DARK = {
    "#56607a": "#9aa3ba", "#4f5bd5": "#8a94ff", "#3a44b0": "#aab1ff", "#8a93a8": "#69728a",
    "#c2410c": "#fb923c", "#15803d": "#4ade80", "#1d4ed8": "#7aa2ff",
  };

  function themed(figure) {
    const dark = window.matchMedia && window.matchMedia("(prefers-color-scheme: dark)").matches;
    if (!dark) return figure;
    return JSON.parse(JSON.stringify(figure).replace(/#[0-9a-f]{6}/g, function (color) {
      return DARK[color] || color;
    }));
  }

  function draw(element, figure) {
    const previous = queues.get(element) || Promise.resolve();
    const next = previous.then(function () {
      const placeholder = element.querySelector(".chart-placeholder");
      if (placeholder) placeholder.remove();
      const colored = themed(figure);
      return plotly.react(element, colored.data, colored.layout, CONFIG);
    }).then(function () {
      element.dataset.drawn = String(Date.now());
    });
    queues.set(element, next.catch(function () {}));
    return next;
  }

  // Loads the bundle if need be, then draws; without WebGL it says so instead.
  function show(element, figure) {
    figure = figure || waiting.get(element);
    waiting.delete(element);
    shown.add(element);
    if (!figure) return Promise.resolve();
    if (!hasWebGL()) {
      say(element, "The 3D view needs WebGL, which this browser does not offer.");
      return Promise.resolve();
    }
    return load(element.dataset.src).then(function () {
      return draw(element, figure);
    }, function () {
      say(element, "The 3D view could not be loaded; the numbers are all in the table.");
    });
  }

  // Live updates: redraws a view that is shown, or keeps the figure for its first show().
  function update(element, figure) {
    if (!shown.has(element)) {
      waiting.set(element, figure);
      return Promise.resolve();
    }
    return show(element, figure);
  }

  // The heading's hint names the mouse's gestures; a touch screen zooms with two fingers.
  const hint = document.getElementById("view3d-hint");
  if (hint && window.matchMedia && window.matchMedia("(pointer: coarse)").matches) {
    hint.textContent = "(drag to rotate, pinch to zoom)";
  }

  // A canvas taller than wide sees less across than up and down: the camera steps back by as
  // much, so that the whole drawing stays framed on a phone (the server frames a square).
  function fitted(camera, element, figureHeight) {
    // The figure's height is what the element gets when Plotly draws; its width, the page's.
    const width = element ? element.clientWidth : 0;
    const height = figureHeight || (element ? element.clientHeight : 0);
    if (!(width > 0 && height > width)) return camera;
    const back = height / width;
    const eye = camera.eye;
    return Object.assign({}, camera, { eye: { x: eye.x * back, y: eye.y * back, z: eye.z * back } });
  }

  return { show: show, update: update, fitted: fitted };
})();
