"""`/v1/presets`: the presets (the paper's cases, a rock drill, a pile) as ready case JSON, also the
request examples in /docs."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException
from pydantic import BaseModel

from percussim.solver.presets import preset_json, preset_names

from .errors import Problem

router = APIRouter(prefix="/v1/presets", tags=["presets"])


class PresetInfo(BaseModel):
    name: str
    description: str


def openapi_examples() -> dict[str, Any] | None:
    """Every preset as an example body of POST /v1/jobs; None when the folder has none."""
    examples = {}
    for name in preset_names():
        case = preset_json(name)
        examples[name] = {"summary": name, "description": case.get("description", ""), "value": case}
    return examples or None


@router.get("", response_model=list[PresetInfo])
def list_presets() -> list[dict]:
    """The presets' names and what each one is."""
    return [{"name": name, "description": preset_json(name).get("description", "")} for name in preset_names()]


@router.get("/{name}", responses={404: {"model": Problem, "description": "no preset of this name"}})
def get_preset(name: str) -> dict:
    """Preset `name` as case JSON, ready to POST to /v1/jobs."""
    try:
        return preset_json(name)
    except KeyError as error:
        raise HTTPException(status_code=404, detail=error.args[0]) from None
