// Numbers for people, the same on the page as on the server (app/web/formatting.py): full
// text as the server wrote it, or a fixed number of decimals; negatives with the real minus
// sign (U+2212). The text given may carry either minus.
"use strict";

window.NumberText = (function () {
  const MINUS = "\u2212";

  function forPeople(text) {
    return text.replace(/-/g, MINUS);
  }

  function format(text, decimals) {
    if (decimals === "full" || decimals === undefined) return forPeople(text);
    const x = Number(text.replace(/\u2212/g, "-"));
    const digits = Number(decimals);
    const size = Math.abs(x);
    if (x === 0 || (size >= 1e-4 && size < 1e15)) return forPeople(x.toFixed(digits));
    return forPeople(x.toExponential(digits));
  }

  return { format: format, forPeople: forPeople };
})();
