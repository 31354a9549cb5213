"""Formulas written twice from one description: as MathML for the page, as plain text beside it.

Chromium renders MathML Core natively, so the worked steps need no script to look like
mathematics; the plain text is the ``alttext`` of each ``<math>`` and what tests read. Each
builder returns a :class:`Formula`; the markup is escaped here, once. For example::

    row(indexed("n", "x"), EQUALS, sqrt(number(49.0)))  # n_x = √(49): <msub>…<msqrt>…

A number is an ``<mn class="num" data-num="…">``: the page's precision setting rewrites its
text (static/js/calculator.js), as it does for the result table.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from markupsafe import Markup, escape

from app.web.formatting import js_number, number_text


@dataclass(frozen=True, slots=True)
class Formula:
    """One piece of a formula: its plain text and its MathML (without the ``<math>`` root).

    ``pieces`` splits a chain ``a = b = c`` where a narrow screen may break it: before each
    "=" or "≈" (MathML Core itself never breaks a line).
    """

    text: str
    markup: str
    pieces: tuple[Formula, ...] = ()

    def __str__(self) -> str:
        return self.text


def _tag(name: str, body: str, attributes: str = "") -> str:
    return f"<{name}{attributes}>{body}</{name}>"


def row(*parts: Formula) -> Formula:
    """Parts side by side; operators carry their own spaces in the text."""
    return Formula("".join(p.text for p in parts), _tag("mrow", "".join(p.markup for p in parts)))


def ident(name: str) -> Formula:
    return Formula(name, _tag("mi", str(escape(name))))


def word(text: str) -> Formula:
    """Words inside a formula ("out of range", " either way"); their outer spaces are kept."""
    body = str(escape(text))
    stripped = body.strip(" ")
    lead, trail = len(body) - len(body.lstrip(" ")), len(body) - len(body.rstrip(" "))
    return Formula(text, _tag("mtext", "\u00a0" * lead + stripped + "\u00a0" * trail))


def op(symbol: str, text: str | None = None) -> Formula:
    """An operator; ``text`` is how the plain text writes it with its spaces (" − ")."""
    return Formula(symbol if text is None else text, _tag("mo", str(escape(symbol))))


EQUALS = op("=", " = ")
APPROX = op("≈", " ≈ ")
MINUS = op("−", " − ")
PLUS = op("+", " + ")
DOT = op("·")
TIMES = op("×", " × ")
ARROW = op("→", " → ")
COMMA = op(",", ", ")


def indexed(name: str, index: str) -> Formula:
    """``n_x``: a name with a subscript."""
    return Formula(f"{name}_{index}", _tag("msub", ident(name).markup + ident(index).markup))


def number(value: float) -> Formula:
    """A double in JavaScript's layout, with the real minus sign; the page may round its text."""
    machine = js_number(value)
    body = str(escape(number_text(value)))
    return Formula(number_text(value), _tag("mn", body, f' class="num" data-num="{machine}"'))


def plain_number(text: str) -> Formula:
    """A number the precision setting leaves alone (a count, an exponent, "NaN")."""
    return Formula(text, _tag("mn", str(escape(text))))


def fenced(inner: Formula, left: str = "(", right: str = ")") -> Formula:
    return Formula(
        f"{left}{inner.text}{right}",
        _tag("mrow", f"<mo>{escape(left)}</mo>{inner.markup}<mo>{escape(right)}</mo>"),
    )


def norm(inner: Formula) -> Formula:
    """``|n|``: the length of a vector."""
    return fenced(inner, "|", "|")


def hat(index: str | None = None) -> Formula:
    """The unit normal n̂, or its component n̂_x."""
    markup = '<mover accent="true"><mi>n</mi><mo>^</mo></mover>'
    if index is None:
        return Formula("n̂", markup)
    return Formula(f"n̂_{index}", _tag("msub", markup + ident(index).markup))


def sqrt(inner: Formula) -> Formula:
    return Formula(f"√({inner.text})", _tag("msqrt", inner.markup))


def square(inner: Formula) -> Formula:
    return Formula(f"{inner.text}²", _tag("msup", inner.markup + "<mn>2</mn>"))


def fraction(top: Formula, bottom: Formula) -> Formula:
    return Formula(f"{top.text} / {bottom.text}", _tag("mfrac", top.markup + bottom.markup))


def joined(parts: Iterable[Formula], separator: Formula) -> Formula:
    items = list(parts)
    pieces: list[Formula] = []
    for index, item in enumerate(items):
        if index:
            pieces.append(separator)
        pieces.append(item)
    return row(*pieces)


def _table(rows: Sequence[Sequence[Formula]]) -> str:
    cells = (
        _tag("mtr", "".join(_tag("mtd", cell.markup) for cell in cells_of_row))
        for cells_of_row in rows
    )
    return _tag("mtable", "".join(cells))


def column(entries: Sequence[Formula]) -> Formula:
    """A column vector in parentheses; the text writes it as a row, ``(1, 2, 3)``."""
    text = "(" + ", ".join(e.text for e in entries) + ")"
    return Formula(text, _tag("mrow", f"<mo>(</mo>{_table([[e] for e in entries])}<mo>)</mo>"))


def determinant(rows: Sequence[Sequence[Formula]]) -> Formula:
    """A determinant between bars; the text writes it ``|a b; c d|``."""
    text = "|" + "; ".join(" ".join(cell.text for cell in cells) for cells in rows) + "|"
    return Formula(text, _tag("mrow", f"<mo>|</mo>{_table(rows)}<mo>|</mo>"))


def _infix(relation: Formula) -> Formula:
    """A relation that starts a piece keeps the spacing it has between two operands."""
    return Formula(relation.text, relation.markup.replace("<mo>", '<mo form="infix">', 1))


def chained(parts: Sequence[Formula]) -> Formula:
    """``parts[0] rel parts[1] rel …`` where every other part is a relation (=, ≈)."""
    pieces = [parts[0], *(row(_infix(parts[i]), parts[i + 1]) for i in range(1, len(parts) - 1, 2))]
    whole = row(*parts)
    return Formula(whole.text, whole.markup, tuple(pieces) if len(pieces) > 1 else ())


def _math(formula: Formula) -> str:
    alt = escape(formula.text.strip())
    return f'<math displaystyle="true" alttext="{alt}">{formula.markup}</math>'


def math(formula: Formula) -> Markup:
    """One line of a step: a ``<div class="formula">`` with the plain text in ``data-formula``.

    A chain is one ``<math>`` a piece, so that the line can wrap between them (``<wbr>``) on a
    phone, each piece with its own plain text as ``alttext``.
    """
    body = "<wbr>".join(_math(piece) for piece in formula.pieces or (formula,))
    return Markup(f'<div class="formula" data-formula="{escape(formula.text)}">{body}</div>')
