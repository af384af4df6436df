"""Configuration of the queue, the records, the results store and the limits, from `PERCUSSIM_*`
variables.

With no broker URL the queue is embedded: Celery's filesystem transport under the results
folder, and with no database URL the records are an SQLite file there too, so one machine needs
no external server. The same code runs against Redis when `PERCUSSIM_BROKER_URL` is set and
PostgreSQL when `PERCUSSIM_DATABASE_URL` is; the difference is only this configuration.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any

from pydantic import BeforeValidator, Field, ValidationError, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from percussim.solver.limits import Limits

PREFIX = "PERCUSSIM_"
REDIS_SCHEMES = ("redis", "rediss", "redis+socket", "sentinel")


def _whole(value: Any) -> Any:
    """A whole number as people write a limit: 20000000, 2e7 or 20_000_000 (else left for the
    integer check to refuse)."""
    if isinstance(value, str):
        text = value.strip().replace("_", "")
        try:
            number = float(text)
        except ValueError:
            return value
        return int(number) if number.is_integer() and abs(number) < 2**63 else value
    return value


Whole = Annotated[int, BeforeValidator(_whole)]
ACCEPTS = {"int_parsing": "a whole number, as 20000000 or 2e7", "float_parsing": "a number, as 2e10"}


class SettingsError(ValueError):
    """`PERCUSSIM_*` variables that cannot be read: one line each, naming the variable, its value
    and what it accepts."""


class Settings(BaseSettings):
    model_config = SettingsConfigDict(env_prefix="PERCUSSIM_")

    broker_url: str | None = Field(default=None, description="e.g. redis://redis:6379/0; none: embedded")
    database_url: str | None = Field(
        default=None,
        description="the job records, e.g. postgresql+psycopg://user:password@db/percussim; "
        "none: an SQLite file in the results folder",
    )
    results_dir: Path = Field(default=Path("percussim-data"), description="the shared results store")
    result_ttl: float | None = Field(
        default=None,
        gt=0,
        description="seconds after which a finished job (or a finished sweep) and its "
        "files are deleted; none: kept until deleted",
    )
    job_time_limit: float = Field(default=900.0, gt=0, description="seconds a job may run")
    stop_grace: float = Field(
        default=10.0,
        ge=0,
        description="seconds a worker told to stop lets its running job finish; then it stops the job, "
        "which goes back on the queue (for another worker, or for the embedded service's next start)",
    )
    redelivery_seconds: float | None = Field(
        default=None,
        gt=0,
        description="seconds after which a job whose worker died is delivered "
        "again (Redis); default job_time_limit + 120, never less",
    )
    max_cells: Whole = Limits.max_cells
    max_steps: Whole = Limits.max_steps
    max_node_steps: float = Limits.max_node_steps
    max_output_values: float = Limits.max_output_values
    max_sweep_variants: Whole = Field(default=1000, ge=1, description="variants one sweep may queue")
    max_body_bytes: Whole = Field(default=2_000_000, ge=1024, description="largest request body accepted")
    api_keys: str | None = Field(default=None, description="comma-separated API keys; none: no keys needed")
    cors_origins: str | None = Field(default=None, description="comma-separated origins browsers may call from")

    @field_validator("broker_url")
    @classmethod
    def _a_redis_broker(cls, url: str | None) -> str | None:
        # The workers' redelivery and the recovery of lost messages read Redis's own keys.
        if url and url.split("://", 1)[0] not in REDIS_SCHEMES:
            raise ValueError(
                "a Redis URL (redis://host:6379/0, rediss://, redis+socket:// or sentinel://), or unset for "
                "the embedded queue"
            )
        return url

    @model_validator(mode="after")
    def _redelivery_after_the_time_limit(self) -> Settings:
        # Sooner, a job still running would be delivered to a second worker.
        if self.redelivery_seconds is not None and self.redelivery_seconds <= self.job_time_limit:
            raise ValueError(
                f"PERCUSSIM_REDELIVERY_SECONDS ({self.redelivery_seconds:g}) must exceed "
                f"PERCUSSIM_JOB_TIME_LIMIT ({self.job_time_limit:g})"
            )
        return self

    @property
    def redelivery(self) -> float:
        return self.redelivery_seconds or self.job_time_limit + 120.0

    @property
    def embedded(self) -> bool:
        return not self.broker_url

    @property
    def broker_folder(self) -> Path:
        return self.results_dir / "broker"

    def api_key_list(self) -> list[str]:
        return _items(self.api_keys)

    def cors_origin_list(self) -> list[str]:
        return _items(self.cors_origins)

    def limits(self) -> Limits:
        return Limits(
            max_cells=self.max_cells,
            max_steps=self.max_steps,
            max_node_steps=self.max_node_steps,
            max_output_values=self.max_output_values,
        )


def _items(text: str | None) -> list[str]:
    return [item.strip() for item in (text or "").split(",") if item.strip()]


def load() -> Settings:
    """The settings from the environment now; `SettingsError` names each bad variable."""
    try:
        return Settings()
    except ValidationError as error:
        lines = []
        for problem in error.errors():
            message = ACCEPTS.get(problem["type"], problem["msg"].removeprefix("Value error, "))
            message = message.replace("Input should be ", "")
            if not problem["loc"]:  # a rule between two variables, which it names itself
                lines.append(message)
                continue
            name = PREFIX + str(problem["loc"][0]).upper()
            lines.append(f"{name}={problem['input']!s}: must be {message}")
        raise SettingsError("\n".join(lines)) from None


@lru_cache
def settings() -> Settings:
    """The settings, read once a process."""
    return load()
