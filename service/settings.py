"""Service configuration from environment variables (pydantic-settings).

``WEARCAST_DATA_DIR`` (default ``./data``) holds the default SQLite database and the raw
uploaded files (content-addressed, see :mod:`wearcast.service.rawfiles`);
``WEARCAST_DATABASE_URL`` (an SQLAlchemy URL) overrides the database, e.g.
``postgresql+psycopg://user@host:5432/wearcast``.

Security and limits (every one a ``WEARCAST_<NAME>`` variable with a safe default):
``WEARCAST_API_KEY`` is the admin key (otherwise the first start creates one and prints it
once); ``WEARCAST_CORS_ORIGINS`` lists the web origins allowed to call the API (none by
default); the ``max_*`` settings bound every request (413/422 naming the limit) and
``rate_limit_*`` every key (429 with ``Retry-After``).

A variable that is set but empty (``WEARCAST_API_KEY=`` in a shell or a compose file) counts
as unset: the setting keeps its default.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import Field, SecretStr, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

MIB = 1024 * 1024


class Settings(BaseSettings):
    """Runtime settings; every field reads ``WEARCAST_<NAME>`` from the environment."""

    model_config = SettingsConfigDict(env_prefix="WEARCAST_", extra="ignore",
                                      env_ignore_empty=True)

    data_dir: Path = Field(default=Path("./data"), description="data directory")
    database_url: str | None = Field(default=None, description="SQLAlchemy URL")
    import_chunk_size: int = Field(default=500, ge=1, description="profiles per bulk insert")
    import_parse_in_workers: bool | None = Field(
        default=None, description="parse long profile CSVs in the import worker processes "
        "(true), in the importing process (false), or when the pool has at least "
        "3 workers (unset; wearcast.service.import_csv_blocks)")

    # --- authentication -------------------------------------------------------------------
    api_key: SecretStr | None = Field(
        default=None, description="the admin API key (Authorization: Bearer <key>); when "
        "unset, the first start creates an admin key and prints it once")
    cors_origins: list[str] = Field(
        default_factory=list, description="web origins allowed by CORS (none by default)")

    # --- limits (413/422 naming the limit) ------------------------------------------------
    max_body_bytes: int = Field(default=2 * MIB, ge=1024,
                                description="largest JSON request body [bytes]")
    max_upload_bytes: int = Field(default=256 * MIB, ge=1024,
                                  description="largest multipart upload [bytes]")
    max_decompressed_bytes: int = Field(default=1024 * MIB, ge=1024,
                                        description="largest total uncompressed zip content")
    max_line_bytes: int = Field(default=1 * MIB, ge=256,
                                description="longest line of an uploaded CSV [bytes]")
    max_columns: int = Field(default=512, ge=8, description="most columns of an uploaded CSV")
    max_zip_members: int = Field(default=20_000, ge=1, description="most members of a zip")
    max_points_per_profile: int = Field(default=20_000, ge=10,
                                        description="most points of one profile")
    max_id_length: int = Field(default=200, ge=8, description="longest id or name [chars]")
    max_fine_bem_poses: int = Field(
        default=10, ge=1, le=100, description="most poses of one POST /v1/contact with "
        "normal_method bem (the fine boundary-element grid, ~0.15-2.5 s of one core per pose; "
        "the other methods take up to 100 at ~2-9 ms each; benchmarks/contact_method_cost.py)")

    # --- rate limits (429 with Retry-After) -----------------------------------------------
    rate_limit_per_second: float = Field(
        default=200.0, ge=0, description="sustained requests per second per key (0: off)")
    rate_limit_burst: int = Field(default=400, ge=1, description="requests a key may burst")

    # --- jobs -------------------------------------------------------------------------------
    job_workers: int = Field(default=2, ge=1, description="in-process job worker threads")
    job_timeout_s: float = Field(default=3600.0, gt=0, description="longest job [s]")
    job_quota_per_key: int = Field(default=8, ge=1,
                                   description="queued or running jobs one key may hold")
    job_wait_s: float = Field(default=300.0, ge=0, le=3600, description=(
        "how long POST /v1/models with kind physics and a physics model's diagnose wait for "
        "their job before answering 202 with it [s]; a request's Prefer: respond-async (0) "
        "or Prefer: wait=N overrides it"))
    job_queue: str = Field(default="embedded", pattern="^(embedded|dramatiq)$",
                           description="embedded (in-process threads) or dramatiq (workers)")
    broker_url: str = Field(default="redis://127.0.0.1:6379/0",
                            description="the Dramatiq broker (Redis) when job_queue=dramatiq")

    @field_validator("api_key", "database_url", mode="before")
    @classmethod
    def _blank_is_unset(cls, value: Any) -> Any:
        """An empty or blank optional value (from the environment or a caller) is unset."""
        raw = value.get_secret_value() if isinstance(value, SecretStr) else value
        if isinstance(raw, str) and not raw.strip():
            return None
        return value

    @property
    def resolved_database_url(self) -> str:
        """The database URL, defaulting to ``sqlite:///<data_dir>/wearcast.sqlite3``."""
        if self.database_url:
            return self.database_url
        return f"sqlite:///{(self.data_dir / 'wearcast.sqlite3').resolve()}"

    @property
    def raw_dir(self) -> Path:
        """Where uploaded files are kept, content-addressed by SHA-256."""
        return self.data_dir / "raw"


def get_settings() -> Settings:
    """Fresh settings from the current environment."""
    return Settings()
