"""The mesh page's samples (/mesh/sample/...): each report says what its description claims, and
the sample's page, its JSON twin and its file are those of an upload of the same file."""

from __future__ import annotations

import asyncio
import functools
import re
import time
from collections import Counter
from collections.abc import Awaitable, Callable
from typing import Any

import httpx
import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient

from app.config import Settings
from app.main import create_app
from app.mesh import work
from app.mesh.samples import CUBE_FACES, SAMPLES, Computed
from app.web.errors import ApiError
from mesh_normal.files import read_mesh
from tests.app.mesh.test_page import json_block, post
from tests.conftest import Page, assert_error

#: What each sample's report must say: its problems (codes), orientation and counts, by hand.
EXPECTED = {
    "cube": {"problems": [], "orientation": "outward", "faces": 12, "watertight": True},
    "inside-out": {"problems": ["inward"], "orientation": "inward", "faces": 12},
    "some-flipped": {"problems": ["winding"], "orientation": "mixed", "faces": 80},
    "open-box": {"problems": ["open"], "faces": 10, "boundary_edges": 4, "watertight": False},
    "degenerate": {"problems": ["degenerate"], "faces": 16, "degenerate_faces": 2},
    "two-pieces": {"problems": ["mixed", "components"], "faces": 24, "components": 2},
}
#: Words of each sample's page: its verdict and diagnosis, as the description promises.
WORDS = {
    "cube": (
        "mesh-verdict",
        "No problems found: the mesh is closed, consistently wound and faces outward",
    ),
    "inside-out": ("problem-inward", "inward"),
    "some-flipped": ("problem-winding", "wound against their neighbours"),
    "open-box": ("problem-open", "The mesh is open"),
    "degenerate": ("problem-degenerate", "2"),
    "two-pieces": ("mesh-objects", "inward"),
}


def test_every_sample_is_listed_with_its_expectation() -> None:
    assert set(SAMPLES) == set(EXPECTED) == set(WORDS)
    for sample in SAMPLES.values():
        assert sample.format in ("obj", "ply")
        assert len(sample.data()) < 4096, sample.name
        assert sample.description.endswith("."), sample.name


@pytest.mark.parametrize("name", list(SAMPLES))
def test_the_report_says_what_the_description_claims(client: TestClient, name: str) -> None:
    answer = client.get(f"/api/mesh/sample/{name}")
    assert answer.status_code == 200, answer.text
    report = answer.json()
    expected = EXPECTED[name]
    assert [p["code"] for p in report["problems"]] == expected["problems"]
    for key, value in expected.items():
        if key != "problems":
            assert report[key] == value, (name, key)
    element, words = WORDS[name]
    response = client.get(f"/mesh/sample/{name}")
    assert response.status_code == 200
    assert words in Page(response.text).text(element)


def test_inside_out_says_inside_out_and_the_fix_flips_all(client: TestClient) -> None:
    html = Page(client.get("/mesh/sample/inside-out").text)
    assert "12 faces are flipped" in html.text("fix-form")
    assert "every face reversed" in html.text("mesh-sample")
    two = Page(client.get("/mesh/sample/two-pieces").text)
    assert "right" in two.text("mesh-object-1") and "inward" in two.text("mesh-object-1")
    assert "outward" in two.text("mesh-object-0")


@pytest.mark.parametrize("name", list(SAMPLES))
def test_page_and_json_twin_equal_the_upload_of_the_file(client: TestClient, name: str) -> None:
    sample = SAMPLES[name]
    download = client.get(f"/mesh/sample/{name}/file")
    assert download.status_code == 200
    assert download.content == sample.data()
    assert download.headers["content-disposition"] == f'attachment; filename="{sample.filename}"'
    uploaded = client.post("/api/mesh", files={"file": (sample.filename, download.content)})
    assert uploaded.status_code == 200
    twin = client.get(f"/api/mesh/sample/{name}")
    assert twin.status_code == 200 and twin.json() == uploaded.json()

    response = client.get(f"/mesh/sample/{name}")
    assert response.template.name == "mesh.html"  # type: ignore[attr-defined]
    html = Page(response.text)
    assert json_block(html, "mesh-report") == uploaded.json()
    assert response.headers["link"] == (
        f'</api/mesh/sample/{name}>; rel="alternate"; type="application/json"'
    )
    assert html.one("link", rel="alternate")["href"] == f"/api/mesh/sample/{name}"
    # The report is the upload's, to the last figure: only the sample line is added.
    upload, _ = post(client, download.content, name=sample.filename, part="report")
    # Without the script an upload's advice names the command (a <noscript> copy): a
    # sample's fixed mesh is a plain link, so its page has no such copy.
    posted = Page(re.sub(r"<noscript>.*?</noscript>", "", upload.text, flags=re.DOTALL))
    fragment = client.get(f"/mesh/sample/{name}", params={"part": "report"})
    assert "<html" not in fragment.text
    shown = Page(fragment.text)
    for element in ("mesh-summary", "mesh-problems"):
        text = shown.text(element).replace(shown.text("mesh-sample"), "")
        assert " ".join(text.split()) == posted.text(element), element
    assert json_block(shown, "mesh-view-data") == json_block(posted, "mesh-view-data")


def test_the_page_links_to_every_sample_without_javascript(client: TestClient) -> None:
    html = Page(client.get("/mesh").text)
    for name in SAMPLES:
        assert html.find("a", href=f"/mesh/sample/{name}"), name
        assert html.find("a", href=f"/mesh/sample/{name}/file"), name
        assert SAMPLES[name].description in html.text(f"sample-{name}")
    current = Page(client.get("/mesh/sample/open-box").text).find("a", href="/mesh/sample/open-box")
    assert any(link.get("aria-current") == "page" for link in current)


@pytest.mark.parametrize(
    "path", ["/api/mesh/sample/nope", "/api/mesh/sample/CUBE", "/api/mesh/sample/cube.obj"]
)
def test_an_unknown_sample_is_a_404_sentence(client: TestClient, path: str) -> None:
    body = assert_error(client.get(path), 404, "name", "no sample mesh named")
    assert "inside-out" in body["error"]


@pytest.mark.parametrize("path", ["/mesh/sample/nope", "/mesh/sample/nope/file"])
def test_an_unknown_sample_page_is_an_html_404(client: TestClient, path: str) -> None:
    response = client.get(path)
    assert response.status_code == 404
    assert response.headers["content-type"].startswith("text/html")
    assert "There is no sample mesh named &#39;nope&#39;" in response.text


def test_a_sample_file_is_written_again_flipped_or_fixed(client: TestClient) -> None:
    """The no-JavaScript export of a sample: a GET of its file with the export's choices."""
    flipped = client.get(
        "/mesh/sample/inside-out/file", params={"format": "ply", "normals": "face", "flip": "true"}
    )
    assert flipped.status_code == 200, flipped.text
    assert flipped.headers["x-faces-flipped"] == "12" and flipped.headers["x-normals"] == "face"
    name = 'attachment; filename="inside-out-export.ply"'
    assert flipped.headers["content-disposition"] == name
    right = read_mesh(flipped.content, "right.ply")
    assert right.faces.tolist() == [list(face) for face in CUBE_FACES]
    fixed = client.get("/mesh/sample/two-pieces/file", params={"fix": "true"})
    assert fixed.headers["x-faces-flipped"] == "12"
    assert fixed.headers["content-disposition"] == 'attachment; filename="two-pieces-fixed.obj"'
    both = client.get("/mesh/sample/cube/file", params={"fix": "true", "flip": "true"})
    assert both.status_code == 422 and "flip and fix cannot both" in both.text


def test_the_sample_export_form_works_without_javascript(client: TestClient) -> None:
    html = Page(client.get("/mesh/sample/open-box").text)
    form = html.one("form", id="export-form")
    assert (form["method"], form["action"]) == ("get", "/mesh/sample/open-box/file")
    assert "hidden" not in form
    names = {e.get("name") for e in html.find("select") + html.find("input") if e.get("name")}
    assert {"format", "normals", "flip"} <= names


def test_captions_and_stored_normals_read_plainly(client: TestClient) -> None:
    html = Page(client.get("/mesh/sample/cube").text)
    assert html.text("mesh-histogram-caption") == "12 faces, all of area 0.5."
    # A tetrahedron whose stored corner normals: 3 agree, 3 point the other way, 6 in between.
    obj = (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 0 0 -1\n"
        "f 1//2 3//2 2//2\nf 1//1 2//1 4//1\nf 1//2 4//2 3//2\nf 2//2 3//2 4//2\n"
    )
    _, page = post(client, obj, name="t.obj", part="report")
    text = page.text("mesh-file-normals")
    assert text.startswith("The file stores 12 corner normals, compared with our angle-weighted")
    assert text.endswith(
        ": 3 agree within 1°, 6 differ by less than 90° (another program's rounding or "
        "weighting, not a problem), 3 point the other way (see the diagnosis)."
    )
    assert "3 normals stored in the file point the other way" in page.text("problem-file_normals")


# --- computed once, then served from memory ------------------------------------------------------


def counting_app(monkeypatch: pytest.MonkeyPatch) -> tuple[FastAPI, Counter[tuple[str, str]]]:
    """An app whose jobs run in its threads, each taking a moment (so that requests overlap),
    and the jobs it ran, by function and sample."""
    app = create_app(settings=Settings(in_process=True))
    jobs: Counter[tuple[str, str]] = Counter()
    run = app.state.jobs.run

    async def counting(request: Any, estimate: int, function: Any, *args: Any) -> Any:
        jobs[function.__name__, args[0].filename] += 1
        return await run(request, estimate, function, *args)

    def slow(real: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(real)
        def slowly(*args: Any) -> Any:
            time.sleep(0.2)
            return real(*args)

        return slowly

    app.state.jobs.run = counting
    for name in ("report", "page", "export"):
        monkeypatch.setattr(work, name, slow(getattr(work, name)))
    return app, jobs


def test_twenty_requests_for_samples_run_one_job_each(monkeypatch: pytest.MonkeyPatch) -> None:
    app, jobs = counting_app(monkeypatch)
    paths = [
        f"{prefix}/{name}{suffix}"
        for name in ("cube", "inside-out")
        for prefix, suffix in (
            ("/api/mesh/sample", ""),
            ("/mesh/sample", ""),
            ("/mesh/sample", "/file?format=stl&fix=true"),
        )
    ]

    async def scenario() -> list[list[httpx.Response]]:
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://test") as client:
            rounds = []
            for _ in range(2):  # all at once, then all again once computed
                requests = [client.get(paths[index % len(paths)]) for index in range(20)]
                rounds.append(list(await asyncio.gather(*requests)))
            return rounds

    rounds = asyncio.run(scenario())
    expected = {
        (function, f"{name}.obj"): 1
        for function in ("report", "page", "export")
        for name in ("cube", "inside-out")
    }
    assert dict(jobs) == expected
    answers: dict[str, set[tuple[int, bytes, str | None]]] = {}
    for answer in rounds[0] + rounds[1]:
        said = (answer.status_code, answer.content, answer.headers.get("content-disposition"))
        answers.setdefault(str(answer.url), set()).add(said)
    assert len(answers) == len(paths)
    for url, said in answers.items():
        assert len(said) == 1 and next(iter(said))[0] == 200, url  # the same answer each time
    fixed = next(iter(answers["http://test/mesh/sample/cube/file?format=stl&fix=true"]))
    assert fixed[2] == 'attachment; filename="cube-fixed.stl"'


def test_a_failed_computation_is_every_waiters_answer_and_is_not_kept() -> None:
    computed = Computed()
    calls: list[int] = []

    async def busy() -> int:
        calls.append(1)
        await asyncio.sleep(0.05)
        raise ApiError(503, "Busy.")

    async def fine() -> int:
        calls.append(2)
        return 7

    async def scenario() -> tuple[list[int | BaseException], int]:
        first = await asyncio.gather(
            *[computed.get("k", busy) for _ in range(3)], return_exceptions=True
        )
        return first, await computed.get("k", fine)

    failures, value = asyncio.run(scenario())
    assert all(isinstance(f, ApiError) and f.status_code == 503 for f in failures)
    assert (calls, value) == ([1, 2], 7)


def test_when_the_first_client_leaves_the_next_one_computes() -> None:
    computed = Computed()
    calls: list[str] = []

    def job(name: str, left: bool) -> Callable[[], Awaitable[str]]:
        async def run() -> str:
            calls.append(name)
            await asyncio.sleep(0.05)
            if left:
                raise ApiError(499, "The client closed the connection before the answer.")
            return name

        return run

    async def scenario() -> list[str | BaseException]:
        first = asyncio.ensure_future(computed.get("k", job("first", True)))
        await asyncio.sleep(0)
        second = computed.get("k", job("second", False))
        return await asyncio.gather(first, second, return_exceptions=True)

    left, value = asyncio.run(scenario())
    assert isinstance(left, ApiError) and left.status_code == 499
    assert value == "second" and calls == ["first", "second"]
