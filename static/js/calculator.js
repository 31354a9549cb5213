// The calculator page: live results, chart and permalink as you type. Without JavaScript the
// form still works (GET, rendered by the server); this script only makes it immediate. The
// server renders every part (GET /partials) from the same templates as the full page.
"use strict";

(function () {
  const FIELDS = ["ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz"];
  // The same rules as the server's (app/calculator/coordinates.py), so a mistake shows
  // before any request: a decimal (its point may be a comma: 2,5) or a fraction of two.
  const NUMBER = "[+-]?(?:[0-9]+(?:\\.[0-9]*)?|\\.[0-9]+|[0-9]+,[0-9]+)(?:[eE][+-]?[0-9]+)?";
  const COORDINATE = new RegExp("^" + NUMBER + "(?:[ \\t\\n\\r\\f\\v]*/[ \\t\\n\\r\\f\\v]*" + NUMBER + ")?$");
  const THOUSANDS = /^[+-]?[1-9][0-9]{0,2},[0-9]{3}$/;
  const MAX_EXACT_EXPONENT = 30;
  const SPACES = /^[ \t\n\r\f\v]+|[ \t\n\r\f\v]+$/g;
  const DELAY_MS = 120;

  const form = document.getElementById("calculator");
  const swap = document.getElementById("swap");
  const result = document.getElementById("result");
  const chart = document.getElementById("chart");
  const precision = document.getElementById("precision");
  const view3d = document.getElementById("view3d");
  let timer = null;
  let inFlight = null;

  // The embed code comes with a relative address when the server has no MESH_PUBLIC_URL (it
  // never builds links from the Host header): this page's own address goes in front.
  const embedCode = document.getElementById("embed-code");
  if (embedCode) embedCode.value = embedCode.value.replace('src="/', 'src="' + location.origin + "/");

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

  function showErrors(errors) {
    FIELDS.concat(["swap"]).forEach(function (name) { setError(name, errors[name]); });
  }

  // A field as people say it: "B.y", not "by" (which reads as the English word).
  function label(name) {
    return name.charAt(0).toUpperCase() + "." + name.slice(1);
  }

  // The fields not filled in yet, said together in one calm line (the server's sentence).
  function missingLine(missing) {
    const said = missing.map(label);
    if (!said.length) return "";
    if (said.length === FIELDS.length) return "All nine coordinates, A.x to C.z, are missing.";
    if (said.length === 1) return said[0] + " is missing.";
    return said.slice(0, -1).join(", ") + " and " + said[said.length - 1] + " are missing.";
  }

  function showMissing(missing) {
    document.getElementById("missing-note").textContent = missingLine(missing);
  }

  function exponent(part) {
    const found = /[eE]([+-]?[0-9]+)$/.exec(part);
    return found ? Math.abs(Number(found[1])) : 0;
  }

  // The server's sentence for a wrong coordinate, or "" (the server has the last word).
  function coordinateError(said, text) {
    if (!COORDINATE.test(text)) {
      const shown = text.length <= 20 ? text : text.slice(0, 17) + "...";
      return said + " must be a number such as 1.5, -2e3 or 1/3, not '" + shown + "'.";
    }
    const parts = text.split("/").map(function (part) { return part.replace(SPACES, ""); });
    const ambiguous = parts.find(function (part) { return THOUSANDS.test(part); });
    if (ambiguous) {
      return said + " is '" + ambiguous + "', which reads as a thousands separator or a decimal comma; write " +
        ambiguous.replace(",", "") + " or " + ambiguous.replace(",", ".") + ".";
    }
    const values = parts.map(function (part) { return Number(part.replace(",", ".")); });
    if (parts.length === 1) {
      return isFinite(values[0]) ? "" : said + " is beyond the double range (about ±1.8e308).";
    }
    if (exponent(parts[0]) > MAX_EXACT_EXPONENT || exponent(parts[1]) > MAX_EXACT_EXPONENT) {
      return said + " is a fraction with an exponent beyond ±" + MAX_EXACT_EXPONENT +
        ", which is not read exactly; write its value as a decimal, such as 3.3e-40.";
    }
    if (values[1] === 0) return said + " divides by zero; a fraction's denominator must not be 0.";
    return "";
  }

  // Wrong values by field, and the fields left blank (not wrong: not given yet).
  function localErrors() {
    const errors = {};
    const missing = [];
    FIELDS.forEach(function (name) {
      const said = label(name);
      const typed = document.getElementById(name).value;
      const text = typed.replace(SPACES, "");
      if (!text) missing.push(name);
      else if (typed.length > 64) {
        errors[name] = said + " is longer than 64 characters; shorten it or use an exponent, such as 1.5e-30.";
      } else {
        const wrong = coordinateError(said, text);
        if (wrong) errors[name] = wrong;
      }
    });
    return { errors: errors, missing: missing };
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

  // Parts that show the last valid points while the form holds a mistake: dimmed, and inert
  // so that nothing (a copy button, say) acts on points that are no longer in the form.
  const LIVE_PARTS = ["steps", "code", "chart", "view3d"];
  const STALE_NOTE = "The numbers shown are for the last valid input; they update once every field is a number.";
  const staleNote = document.getElementById("stale-note");
  // Whether the page shows a result at all (a permalink with a mistake opens without one).
  let shown = JSON.parse(document.getElementById("figure-data").textContent) !== null;

  function setStale(stale) {
    result.classList.toggle("stale", stale);
    LIVE_PARTS.forEach(function (id) {
      const part = document.getElementById(id);
      if (!part) return;
      part.classList.toggle("stale", stale);
      part.inert = stale;
    });
    if (staleNote) staleNote.textContent = stale && shown ? STALE_NOTE : "";
  }

  function showInvalid(count) {
    const slot = result.querySelector('[data-key="invalid"]');
    slot.textContent = count ?
      "Fix the highlighted " + (count === 1 ? "field" : "fields") + " to see the normal." :
      "Fill in every coordinate to see the normal.";
    slot.classList.toggle("error", count > 0);
    slot.classList.remove("hidden");
    setStale(true);
  }

  // Display precision: the server writes every number in full (data-num); this rewrites the
  // text only, so copying, JSON and downloads keep every digit.
  function formatNumber(text, decimals) {
    return window.NumberText.format(text, decimals);  // static/js/numbers.js
  }

  function applyPrecision() {
    const decimals = precision ? precision.value : "full";
    document.querySelectorAll(".num[data-num]").forEach(function (el) {
      el.textContent = formatNumber(el.dataset.num, decimals);
    });
  }

  function render(parts) {
    Object.keys(parts.html).forEach(function (id) {
      const target = document.getElementById(id);
      if (!target) return;
      // Keep the reader's open and closed sections as they were.
      const open = {};
      target.querySelectorAll("details[id]").forEach(function (d) { open[d.id] = d.open; });
      target.innerHTML = parts.html[id];
      target.querySelectorAll("details[id]").forEach(function (d) {
        if (d.id in open) d.open = open[d.id];
      });
    });
    shown = true;
    setStale(false);
    applyPrecision();
    document.dispatchEvent(new CustomEvent("calculator:rendered", { detail: parts }));
    if (view3d && parts.view3d && window.NormalView3D) window.NormalView3D.update(view3d, parts.view3d);
    return window.NormalChart.draw(chart, parts.figure);
  }

  function update() {
    const qs = query();
    updateLinks(qs);
    const local = localErrors();
    showErrors(local.errors);
    showMissing(local.missing);
    const count = Object.keys(local.errors).length;
    // An answer still on its way is for older input: it must not land after this.
    if (inFlight) inFlight.abort();
    inFlight = null;
    if (count || local.missing.length) { showInvalid(count); return Promise.resolve(); }
    inFlight = new AbortController();
    return fetch("/partials?" + qs, { signal: inFlight.signal, headers: { Accept: "application/json" } })
      .then(function (response) { return response.json(); })
      .then(function (parts) {
        const serverErrors = Object.keys(parts.errors).length;
        showErrors(parts.errors);
        showMissing(parts.missing);
        if (serverErrors || parts.missing.length) { showInvalid(serverErrors); return; }
        return render(parts);
      })
      .catch(function (error) {
        if (error.name !== "AbortError") console.warn("update failed:", error.message);
      });
  }

  function schedule() {
    clearTimeout(timer);
    timer = setTimeout(update, DELAY_MS);
  }

  function copyText(source) {
    return source.value !== undefined && source.tagName === "TEXTAREA" ? source.value : source.textContent;
  }

  function copy(button) {
    const source = document.getElementById(button.dataset.copy);
    const label = button.textContent;
    const done = function () {
      button.textContent = "Copied";
      setTimeout(function () { button.textContent = label; }, 1500);
    };
    if (navigator.clipboard && window.isSecureContext) {
      navigator.clipboard.writeText(copyText(source)).then(done, function () {});
    } else if (source.select) {
      source.select();
      document.execCommand("copy");
      done();
    }
  }

  function loadPreset(link) {
    const params = new URL(link.href).searchParams;
    FIELDS.forEach(function (name) { document.getElementById(name).value = params.get(name) || ""; });
    swap.checked = params.get("swap") === "on";
    clearTimeout(timer);
    return update();
  }

  // Pasted text that holds 3 numbers ("1, 2, 3", "1 2 3", "(1, 2, 3)", tab-separated) or 9,
  // split as people write them: by spaces, tabs, semicolons or ", "; else by bare commas
  // ("1,2,3"), so that "1,5 2,5 3,5" keeps its decimal commas. null when it is no such list
  // of numbers (then the text is pasted as it is, into the one field).
  function pastedNumbers(text) {
    const inner = text.replace(/[()[\]{}]/g, " ").trim();
    const notEmpty = function (part) { return part !== "" && part !== ","; };
    let parts = inner.split(/[\s;]*;[\s;]*|,\s+|\s+/).filter(notEmpty);
    const numbers = function (list) {
      return (list.length === 3 || list.length === 9) && list.every(function (part) { return COORDINATE.test(part); });
    };
    if (!numbers(parts)) parts = inner.split(/[\s,;]+/).filter(notEmpty);
    return numbers(parts) ? parts : null;
  }

  // Pasting a point into any of its fields fills x, y and z; nine numbers fill every field.
  form.addEventListener("paste", function (event) {
    const name = event.target.id;
    if (FIELDS.indexOf(name) < 0 || !event.clipboardData) return;
    const parts = pastedNumbers(event.clipboardData.getData("text"));
    if (!parts) return;
    event.preventDefault();
    const first = parts.length === 9 ? 0 : FIELDS.indexOf(name[0] + "x");
    parts.forEach(function (part, i) { document.getElementById(FIELDS[first + i]).value = part; });
    document.getElementById(FIELDS[first + parts.length - 1]).focus();
    clearTimeout(timer);
    update();
  });

  form.addEventListener("input", schedule);
  swap.addEventListener("change", function () { clearTimeout(timer); update(); });
  form.addEventListener("submit", function (event) {
    event.preventDefault();
    clearTimeout(timer);
    update();
  });
  // Copy buttons and presets may be re-rendered, so listen on the document.
  document.addEventListener("click", function (event) {
    const button = event.target.closest("button[data-copy]");
    if (button) { copy(button); return; }
    const preset = event.target.closest("a.preset");
    if (preset && !event.ctrlKey && !event.metaKey && !event.shiftKey) {
      event.preventDefault();
      loadPreset(preset);
    }
  });
  if (precision) {
    const saved = window.localStorage && localStorage.getItem("precision");
    if (saved && precision.querySelector('option[value="' + saved + '"]')) precision.value = saved;
    precision.addEventListener("change", function () {
      if (window.localStorage) localStorage.setItem("precision", precision.value);
      applyPrecision();
    });
    applyPrecision();
  }
  // The 3D part of Plotly loads only once the view scrolls into sight and the page is idle,
  // so the first load stays small and the bar chart draws first.
  function start3d() {
    if (!view3d || !window.NormalView3D) return;
    const initial = JSON.parse(document.getElementById("view3d-data").textContent);
    const whenIdle = window.requestIdleCallback || function (callback) { setTimeout(callback, 200); };
    const observer = new IntersectionObserver(function (entries) {
      if (!entries.some(function (entry) { return entry.isIntersecting; })) return;
      observer.disconnect();
      whenIdle(function () { window.NormalView3D.show(view3d, initial); });
    });
    observer.observe(view3d);
  }

  window.NormalChart.drawFromPage().then(start3d);
  window.calculatorUpdate = update;  // lets browser tests wait for a settled page
})();
