"""Service configuration from environment variables (pydantic-settings).

``WEARCAST_DATA_DIR`` (default ``./data``) holds the default SQLite database and the raw
uploaded files (content-addressed, see :mod:`wearcast.service.rawfiles`);
``WEARCAST_DATABASE_URL`` (an SQLAlchemy URL) overrides the database, e.g.
``postgresql+psycopg://user@host:5432/wearcast``.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    """Runtime settings; every field reads ``WEARCAST_<NAME>`` from the environment."""

    model_config = SettingsConfigDict(env_prefix="WEARCAST_", extra="ignore")

    data_dir: Path = Field(default=Path("./data"), description="data directory")
    database_url: str | None = Field(default=None, description="SQLAlchemy URL")
    import_chunk_size: int = Field(default=500, ge=1, description="profiles per bulk insert")

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
