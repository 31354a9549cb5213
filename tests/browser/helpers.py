"""Small helpers shared by the browser tests: filling the form and waiting for the chart."""

from __future__ import annotations

import re
from collections.abc import Sequence
from urllib.parse import urlencode

from playwright.sync_api import Error, Locator, Page

FIELDS = ("ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz")
Point = Sequence[str]

RIGHT = (("0", "0", "0"), ("1", "0", "0"), ("0", "1", "0"))
COLLINEAR = (("0", "0", "0"), ("1", "1", "1"), ("2", "2", "2"))


def triangle_query(a: Point, b: Point, c: Point, *, swap: bool = False) -> str:
    params = dict(zip(FIELDS, [*a, *b, *c], strict=True))
    if swap:
        params["swap"] = "on"
    return urlencode(params)


def query_pattern(a: Point, b: Point, c: Point) -> re.Pattern[str]:
    """Matches a URL whose query carries exactly these coordinates, in the form's order."""
    return re.compile(r"\?" + re.escape(triangle_query(a, b, c)) + r"(&|$)")


def fill_triangle(page: Page, a: Point, b: Point, c: Point) -> None:
    for name, value in zip(FIELDS, [*a, *b, *c], strict=True):
        page.locator(f"#{name}").fill(value)


def open_calculator(page: Page, query: str = "") -> None:
    """Open the calculator (with a query) and wait until its chart is drawn."""
    response = page.goto("/" + (f"?{query}" if query else ""))
    assert response is not None and response.status == 200, response and response.status
    page.locator("#chart[data-drawn] .main-svg").first.wait_for()


def cell(page: Page, key: str) -> Locator:
    """A cell of the result table, by its data-key."""
    return page.locator(f'#result [data-key="{key}"]')


def chart_values(page: Page) -> object:
    """The bars' values as Plotly holds them (the bars are horizontal: values along x)."""
    return page.evaluate(
        "() => { const c = document.getElementById('chart');"
        " return c && c.data ? c.data[0].x : null; }"
    )


def wait_for_chart_values(page: Page, values: list[float], timeout: float = 10_000) -> None:
    """Wait until Plotly has drawn exactly ``values`` into #chart (read from the element)."""
    try:
        page.wait_for_function(
            """(want) => {
                const c = document.getElementById('chart');
                const y = c && c.dataset.drawn && c.data && c.data[0] && c.data[0].x;
                return Boolean(y && c.querySelector('.main-svg') && y.length === want.length
                               && want.every((value, i) => y[i] === value));
            }""",
            arg=values,
            timeout=timeout,
        )
    except Error as error:
        raise AssertionError(
            f"chart values are {chart_values(page)!r}, expected {values!r}"
        ) from error


#: An init script that lets a test hold the page's fetch answers back and then release them,
#: to play out a slow network deterministically. ``window.__held`` counts requests waiting at
#: the gate; ``window.__settled`` counts answers the page has finished reading (or that failed),
#: bumped one task later, so the page's own promise callbacks have run by then.
FETCH_GATE = """
(() => {
  window.__held = 0;
  window.__settled = 0;
  window.__holdFetches = false;
  let open;
  const gate = new Promise((resolve) => { open = resolve; });
  window.__openGate = () => open();
  const later = () => setTimeout(() => { window.__settled += 1; }, 0);
  const fetch0 = window.fetch.bind(window);
  window.fetch = function (...args) {
    const hold = window.__holdFetches;
    return fetch0(...args).then(async (response) => {
      if (hold) { window.__held += 1; await gate; }
      const json0 = response.json.bind(response);
      response.json = () => json0().finally(later);
      return response;
    }, (error) => { later(); throw error; });
  };
})();
"""
