// The calculator page: live results, chart and permalink as you type. Without JavaScript the
// form still works (GET, rendered by the server); this script only makes it immediate.
"use strict";

(function () {
  const FIELDS = ["ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz"];
  // The same rule as the server's (app/params.py), so a mistake shows before any request.
  const DECIMAL = /^[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$/;
  const DELAY_MS = 120;

  const form = document.getElementById("calculator");
  const swap = document.getElementById("swap");
  const result = document.getElementById("result");
  const chart = document.getElementById("chart");
  let timer = null;
  let inFlight = null;

  function num(x) {
    return x === null ? "out of range" : String(x);
  }

  function vec(v) {
    return v === null ? "none" : "(" + v.map(num).join(", ") + ")";
  }

  function cell(key) {
    return result.querySelector('[data-key="' + key + '"]');
  }

  function setError(name, sentence) {
    const slot = form.querySelector('[data-error-for="' + name + '"]');
    const input = document.getElementById(name);
    if (slot) slot.textContent = sentence || "";
    if (input) {
      if (sentence) input.setAttribute("aria-invalid", "true");
      else input.removeAttribute("aria-invalid");
      const box = input.closest(".coord");
      if (box) box.classList.toggle("invalid", Boolean(sentence));
    }
  }

  function localErrors() {
    const errors = {};
    FIELDS.forEach(function (name) {
      const typed = document.getElementById(name).value;
      const text = typed.replace(/^[ \t\n\r\f\v]+|[ \t\n\r\f\v]+$/g, "");
      if (!text) errors[name] = name + " is empty; enter a decimal number such as 1.5.";
      else if (typed.length > 64) {
        errors[name] = name + " is longer than 64 characters; shorten it or use an exponent, such as 1.5e-30.";
      } else if (!DECIMAL.test(text)) {
        const shown = text.length <= 20 ? text : text.slice(0, 17) + "...";
        errors[name] = name + " must be a decimal number such as 1.5 or -2e3, not '" + shown + "'.";
      } else if (!isFinite(Number(text))) {
        errors[name] = name + " is beyond the double range (about ±1.8e308).";
      }
    });
    return errors;
  }

  function query() {
    const params = new URLSearchParams();
    FIELDS.forEach(function (name) { params.set(name, document.getElementById(name).value); });
    if (swap.checked) params.set("swap", "on");
    return params.toString();
  }

  function updateLinks(qs) {
    history.replaceState(null, "", "/?" + qs);
    document.getElementById("json-link").href = "/api/normal?" + qs;
    document.getElementById("json-alternate").href = "/api/normal?" + qs;
    document.getElementById("chart-link").href = "/api/chart?" + qs;
    const code = document.getElementById("embed-code");
    code.value = code.value.replace(/embed\?[^"]*/, "embed?" + qs);
  }

  function showInvalid(count) {
    const slot = cell("invalid");
    slot.textContent = "Fix the highlighted " + (count === 1 ? "field" : "fields") + " to see the normal.";
    slot.classList.remove("hidden");
    result.classList.add("stale");
  }

  function fill(p) {
    cell("invalid").classList.add("hidden");
    result.classList.remove("stale");
    cell("order").textContent = "order " + p.order.split("").join(", ");
    cell("u-from").textContent = p.order[1];
    cell("v-from").textContent = p.order[2];
    ["u", "v", "normal"].forEach(function (key) { cell(key).textContent = vec(p[key]); });
    cell("magnitude").textContent = num(p.magnitude);
    cell("area").textContent = num(p.area);
    cell("unit_normal").textContent = p.unit_normal ? vec(p.unit_normal) : "none (degenerate triangle)";
    const message = cell("message");
    message.textContent = p.message || "";
    message.classList.toggle("hidden", !p.message);
    message.classList.toggle("warn", p.degenerate);
  }

  function fetchJson(url, signal) {
    return fetch(url, { signal: signal, headers: { Accept: "application/json" } }).then(function (r) {
      return r.json().then(function (body) { return { ok: r.ok, body: body }; });
    });
  }

  function update() {
    const qs = query();
    updateLinks(qs);
    const errors = localErrors();
    FIELDS.forEach(function (name) { setError(name, errors[name]); });
    setError("swap", "");
    const count = Object.keys(errors).length;
    // An answer still on its way is for older input: it must not land after this.
    if (inFlight) inFlight.abort();
    inFlight = null;
    if (count) { showInvalid(count); return Promise.resolve(); }
    inFlight = new AbortController();
    const signal = inFlight.signal;
    return Promise.all([fetchJson("/api/normal?" + qs, signal), fetchJson("/api/chart?" + qs, signal)])
      .then(function (answers) {
        const normal = answers[0];
        const figure = answers[1];
        if (!normal.ok) {
          if (normal.body.field) setError(normal.body.field, normal.body.error);
          showInvalid(1);
          return;
        }
        fill(normal.body);
        return window.NormalChart.draw(chart, figure.body);
      })
      .catch(function (error) {
        if (error.name !== "AbortError") console.warn("update failed:", error.message);
      });
  }

  function schedule() {
    clearTimeout(timer);
    timer = setTimeout(update, DELAY_MS);
  }

  function copy(button) {
    const source = document.getElementById(button.dataset.copy);
    const done = function () {
      button.textContent = "Copied";
      setTimeout(function () { button.textContent = "Copy"; }, 1500);
    };
    if (navigator.clipboard && window.isSecureContext) {
      navigator.clipboard.writeText(source.value).then(done, function () { source.select(); });
    } else {
      source.select();
      document.execCommand("copy");
      done();
    }
  }

  form.addEventListener("input", schedule);
  swap.addEventListener("change", function () { clearTimeout(timer); update(); });
  form.addEventListener("submit", function (event) {
    event.preventDefault();
    clearTimeout(timer);
    update();
  });
  document.querySelectorAll("button[data-copy]").forEach(function (button) {
    button.addEventListener("click", function () { copy(button); });
  });
  window.NormalChart.drawFromPage();
  window.calculatorUpdate = update;  // lets browser tests wait for a settled page
})();
