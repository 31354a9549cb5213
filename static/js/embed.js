"use strict";
document.addEventListener("DOMContentLoaded", function () {
  window.NormalChart.drawFromPage();
});
