// Keeps the Plotly toolbars (modebars) out of the Tab order, where each would add up to nine
// stops per chart. Each chart with a toolbar gets one "Chart tools" button instead, shown when
// it has focus, that lets the keyboard into that toolbar; leaving the toolbar (Tab past it, or
// Escape) shuts it again. Plotly rebuilds its buttons on many redraws, so an observer catches
// every new one, on any page and for charts drawn at any time.
"use strict";

(function () {
  const OPEN = "chart-tools-open";

  function reachable(chart, open) {
    chart.classList.toggle(OPEN, open);
    chart.querySelectorAll(".modebar-btn").forEach(function (button) {
      if (open) button.removeAttribute("tabindex");
      else button.setAttribute("tabindex", "-1");
    });
  }

  function addToggle(chart) {
    if (chart.dataset.chartTools) return;
    chart.dataset.chartTools = "on";
    const toggle = document.createElement("button");
    toggle.type = "button";
    toggle.className = "chart-tools small";
    toggle.textContent = "Chart tools";
    toggle.setAttribute("aria-label", "Chart tools: download as an image, zoom, pan, reset");
    toggle.addEventListener("click", function () {
      reachable(chart, true);
      const first = chart.querySelector(".modebar-btn");
      if (first) first.focus();
    });
    chart.addEventListener("focusout", function (event) {
      if (!chart.contains(event.relatedTarget)) reachable(chart, false);
    });
    chart.addEventListener("keydown", function (event) {
      if (event.key !== "Escape" || !chart.classList.contains(OPEN)) return;
      reachable(chart, false);
      toggle.focus();
    });
    chart.parentNode.classList.add("has-chart-tools");
    chart.parentNode.insertBefore(toggle, chart);
  }

  function tame() {
    document.querySelectorAll(".modebar-btn:not([tabindex])").forEach(function (button) {
      const chart = button.closest(".js-plotly-plot");
      if (!chart || chart.classList.contains(OPEN)) return;
      button.setAttribute("tabindex", "-1");
      addToggle(chart);
    });
  }

  new MutationObserver(tame).observe(document.body, { childList: true, subtree: true });
  tame();
})();
