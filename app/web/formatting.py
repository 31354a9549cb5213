"""Numbers as text, the way JavaScript's ``String(x)`` writes them.

The page renders numbers on the server (JavaScript off) and in the browser (live updates);
both must read the same, so the server follows ECMAScript's Number::toString and, for a
fixed number of decimals, static/js/numbers.js. Text for people writes negatives with the
real minus sign (U+2212); text for machines (JSON, CSV, code, data attributes) keeps "-".
"""

from __future__ import annotations

from decimal import ROUND_HALF_UP, Decimal

MINUS = "\u2212"

#: Fixed decimals read well from here up to here; outside, the exponent form does.
FIXED_RANGE = (1e-4, 1e15)


def js_number(x: float) -> str:
    """Return the shortest round-trip text of ``x`` in JavaScript's layout.

    >>> js_number(1e-7), js_number(1e21), js_number(0.5), js_number(-0.0)
    ('1e-7', '1e+21', '0.5', '0')
    """
    if x == 0:
        return "0"
    text = repr(x)
    if "e" not in text and "n" not in text:
        # 1e-4 <= |x| < 1e16: both write the same shortest digits without an exponent.
        return text[:-2] if text.endswith(".0") else text
    return _exponent_layout(x)


def _exponent_layout(x: float) -> str:
    """:func:`js_number` from the digits and the exponent (``x`` nonzero)."""
    sign = "-" if x < 0 else ""
    _, digit_tuple, exponent = Decimal(repr(abs(x))).normalize().as_tuple()
    digits = "".join(map(str, digit_tuple))
    k = len(digits)
    n = k + int(exponent)  # the value is 0.digits * 10**n
    if k <= n <= 21:
        text = digits + "0" * (n - k)
    elif 0 < n <= 21:
        text = digits[:n] + "." + digits[n:]
    elif -6 < n <= 0:
        text = "0." + "0" * -n + digits
    else:
        mantissa = digits[0] + ("." + digits[1:] if k > 1 else "")
        text = f"{mantissa}e{'+' if n - 1 >= 0 else '-'}{abs(n - 1)}"
    return sign + text


def for_people(text: str) -> str:
    """Machine text with the real minus sign: ``-1e-7`` reads ``−1e−7``."""
    return text.replace("-", MINUS)


def decimals_text(x: float, decimals: int) -> str:
    """``x`` with ``decimals`` digits after the point, as JavaScript's toFixed / toExponential.

    Both round the exact value half away from zero, and so does this.

    >>> decimals_text(0.0, 4), decimals_text(-1.5, 4), decimals_text(1e20, 2)
    ('0.0000', '−1.5000', '1.00e+20')
    """
    if x == 0:
        return f"{0:.{decimals}f}"
    size = abs(x)
    if FIXED_RANGE[0] <= size < FIXED_RANGE[1]:
        text = str(Decimal(x).quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP))
    else:
        exponent = Decimal(size).adjusted()
        mantissa = (
            Decimal(x)
            .scaleb(-exponent)
            .quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP)
        )
        if abs(mantissa) >= 10:  # 9.995 rounds up to 10.00: one more power of ten
            exponent += 1
            mantissa = (
                Decimal(x)
                .scaleb(-exponent)
                .quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP)
            )
        text = f"{mantissa}e{'+' if exponent >= 0 else '-'}{abs(exponent)}"
    return for_people(text)


def number_text(x: float, decimals: int | None = None) -> str:
    """A number for people: in full (JavaScript's layout) or with ``decimals`` decimals."""
    return for_people(js_number(x)) if decimals is None else decimals_text(x, decimals)
