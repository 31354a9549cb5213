"""Numbers as text, the way JavaScript's ``String(x)`` writes them.

The page renders numbers on the server (JavaScript off) and in the browser (live updates);
both must read the same, so the server follows ECMAScript's Number::toString.
"""

from __future__ import annotations

from decimal import Decimal


def js_number(x: float) -> str:
    """Return the shortest round-trip text of ``x`` in JavaScript's layout.

    >>> js_number(1e-7), js_number(1e21), js_number(0.5), js_number(-0.0)
    ('1e-7', '1e+21', '0.5', '0')
    """
    if x == 0:
        return "0"
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
