"""The job page: `/` and its static files (HTML, CSS and JS as ES modules, without a build step; no
resource from anywhere else; docs/architecture.md lists the modules). The plots are drawn by Plotly's cartesian bundle, kept here as it is published
(`npm pack plotly.js-cartesian-dist-min`, MIT, its licence beside it).

Served without an API key: the page holds no data; it asks for a key and sends it in
`X-API-Key` with every `/v1` call it makes.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, HTTPException
from fastapi.responses import FileResponse

STATIC = Path(__file__).resolve().parent / "static"
_TYPES = {".html": "text/html", ".js": "text/javascript", ".css": "text/css"}

router = APIRouter(include_in_schema=False)


def _files() -> dict[str, Path]:
    # Names are looked up among the files present, never joined into a path, so "../x" reaches nothing.
    return {p.name: p for p in STATIC.iterdir() if p.suffix in _TYPES}


def _serve(path: Path) -> FileResponse:
    # no-cache: the browser revalidates (cheap, by ETag), so a new version of the page is seen at once.
    return FileResponse(path, media_type=_TYPES[path.suffix], headers={"Cache-Control": "no-cache"})


@router.get("/")
def page() -> FileResponse:
    return _serve(STATIC / "index.html")


@router.get("/static/{name}")
def static(name: str) -> FileResponse:
    path = _files().get(name)
    if path is None:
        raise HTTPException(status_code=404, detail=f"no static file {name!r}")
    return _serve(path)
