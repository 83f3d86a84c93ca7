"""Pictures answer with a strong ETag of their inputs: ``If-None-Match`` naming it gets 304,
changed data give another ETag, and a picture is drawn once per inputs
(:mod:`wearcast.service.picture_cache`)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.service.conftest import calibrate_on_metro
from wearcast.service import picture_cache
from wearcast.service.app import create_app
from wearcast.service.picture_cache import PictureJob, RenderedCache, picture_key
from wearcast.service.settings import Settings
from wearcast.statistics.generators import fleet_twin as ft
from wearcast.statistics.generators import twin_routes

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    from fastapi.testclient import TestClient

WHERE = {"route_id": "metro", "bogie_type": "motor", "axle": 1, "side": "left"}


@pytest.fixture(scope="module")
def fleet() -> pd.DataFrame:
    config = ft.FleetConfig(
        units=(ft.UnitConfig("B", twin_routes.metro_route(), vehicles=1, running_mode="lead"),),
        mileages_km=(30_000, 80_000, 130_000), mileage_jitter_km=0.0,
        calibration_factor={"tread": 1.5e-6, "flange": 6.0e-6}, rate_scatter=0.0,
        area_scatter=0.0, noise_mm=0.005, points_per_profile=300, seed=7)
    return ft.generate_fleet(config).profiles


@pytest.fixture
def setup(tmp_path: Path, fleet: pd.DataFrame) -> dict:
    client = TestClient(create_app(Settings(data_dir=tmp_path)))
    made = calibrate_on_metro(client, fleet, "metro", {"route_id": "metro"})
    return {"client": client, "model_id": made["model"]["id"]}


def test_a_picture_answers_304_to_its_etag(setup: dict) -> None:
    client, url = setup["client"], f"/v1/models/{setup['model_id']}/pictures/wear-area"
    first = client.get(url, params=WHERE)
    assert first.status_code == 200 and first.content.startswith(b"<?xml")
    etag = first.headers["etag"]
    assert etag.startswith('"') and etag.endswith('"') and len(etag) > 20  # strong
    assert "no-cache" in first.headers["cache-control"]
    assert "private" in first.headers["cache-control"]
    again = client.get(url, params=WHERE, headers={"If-None-Match": etag})
    assert again.status_code == 304 and again.content == b""
    assert again.headers["etag"] == etag
    listed = client.get(url, params=WHERE, headers={"If-None-Match": f'"other", W/{etag}'})
    assert listed.status_code == 304  # weak comparison, any listed tag
    other = client.get(url, params=WHERE, headers={"If-None-Match": '"something-else"'})
    assert other.status_code == 200 and other.content == first.content
    # another format or position is another picture
    png = client.get(url, params={**WHERE, "format": "png"}, headers={"If-None-Match": etag})
    assert png.status_code == 200 and png.content.startswith(b"\x89PNG")
    assert png.headers["etag"] != etag
    right = client.get(url, params={**WHERE, "side": "right"})
    assert right.status_code == 200 and right.headers["etag"] != etag
    # errors are not cached answers
    missing = client.get(url, params={**WHERE, "route_id": "nowhere"},
                         headers={"If-None-Match": etag})
    assert missing.status_code == 404 and "etag" not in missing.headers


def test_a_picture_is_drawn_once_per_inputs(setup: dict) -> None:
    client, url = setup["client"], f"/v1/models/{setup['model_id']}/pictures/profile"
    params = {**WHERE, "mileage_km": 80_000}
    picture_cache.RENDERED.clear()
    first = client.get(url, params=params)
    assert first.status_code == 200
    assert picture_cache.RENDERED.misses == 1 and picture_cache.RENDERED.hits == 0
    second = client.get(url, params=params)
    assert second.content == first.content and second.headers["etag"] == first.headers["etag"]
    assert picture_cache.RENDERED.misses == 1 and picture_cache.RENDERED.hits == 1
    assert client.get(url, params={**params, "mileage_km": 90_000}).status_code == 200
    assert picture_cache.RENDERED.misses == 2


def test_changed_data_give_another_etag(setup: dict, fleet: pd.DataFrame) -> None:
    client, model_id = setup["client"], setup["model_id"]
    url = f"/v1/models/{model_id}/pictures/wear-area"
    before = client.get(url, params=WHERE)
    etag = before.headers["etag"]
    # one more wheel measured at that position on that route: its points join the picture
    extra = fleet[(fleet.wheel_id == "B1-M1L") & (fleet.mileage_km == 80_000)].copy()
    extra["wheel_id"], extra["vehicle_id"], extra["mileage_km"] = "B9-M1L", "B9", 100_000
    r = client.post("/v1/measurements/import", files={"file": (
        "extra.csv", extra.to_csv(index=False).encode(), "text/csv")})
    assert r.status_code == 200 and r.json()["created"] == 1, r.text
    after = client.get(url, params=WHERE, headers={"If-None-Match": etag})
    assert after.status_code == 200 and after.headers["etag"] != etag
    assert after.content != before.content

    # a measurement taken against another reference is another picture
    item = client.get("/v1/measurements", params={"wheel_id": "B1-M1L"}).json()["items"][0]
    purl = f"/v1/measurements/{item['id']}/pictures/profile"
    profile = client.get(purl)
    assert profile.status_code == 200 and "reference S1002" in profile.text
    petag = profile.headers["etag"]
    assert client.get(purl, headers={"If-None-Match": petag}).status_code == 304
    changed = client.put("/v1/wheels/B1-M1L/reference",
                         json={"reference_profile": "S1002/30.5"})
    assert changed.status_code == 200, changed.text
    redrawn = client.get(purl, headers={"If-None-Match": petag})
    assert redrawn.status_code == 200 and redrawn.headers["etag"] != petag
    assert "S1002/30.5" in redrawn.text


def test_the_wheel_picture_answers_304(setup: dict) -> None:
    client = setup["client"]
    url = "/v1/wheels/B1-M1L/pictures/parameters"
    params = {"model_id": setup["model_id"], "route_id": "metro"}
    first = client.get(url, params=params)
    assert first.status_code == 200, first.text
    again = client.get(url, params=params, headers={"If-None-Match": first.headers["etag"]})
    assert again.status_code == 304


def _job(values: np.ndarray, title: str = "t") -> PictureJob:
    def build(frame: pd.DataFrame, *, title: str) -> bytes:
        return f"{title}:{frame.to_numpy().sum()}".encode()

    frame = pd.DataFrame({"mileage_km": [1.0, 2.0], "area": values})
    return PictureJob(build, (frame,), {"title": title})


def test_the_key_follows_every_input() -> None:
    base = picture_key(_job(np.array([1.0, 2.0])))
    assert base is not None and base == picture_key(_job(np.array([1.0, 2.0])))
    assert picture_key(_job(np.array([1.0, 2.0000001]))) != base
    assert picture_key(_job(np.array([1.0, 2.0]), title="u")) != base
    unknown = PictureJob(_job(np.zeros(2)).build, (object(),), {})
    assert picture_key(unknown) is None  # never cached under an incomplete key
    assert picture_cache.render(_job(np.array([1.0, 2.0]))) == b"t:6.0"


def test_the_key_of_text_columns_and_number_lists_is_unambiguous() -> None:
    """Text columns and lists of floats are hashed in one piece each (speed): the pieces'
    boundaries and types still count."""
    def key(*args: object) -> str | None:
        return picture_key(PictureJob(_job(np.zeros(2)).build, args, {}))

    assert key(np.array(["ab", "c"], dtype=object)) != key(np.array(["a", "bc"], dtype=object))
    assert key(np.array(["a", "b"], dtype=object)) != key(np.array(["a", None], dtype=object))
    assert key(np.array(["é"], dtype=object)) == key(np.array(["é"], dtype=object))
    assert key([1.0, 2.0]) != key([1.0, 2]) != key((1.0, 2.0, 0.0))
    assert key([1.0, 2.0]) != key(np.array([1.0, 2.0]))
    assert key([1.0, 2.0]) == key([1.0, 2.0]) != key([2.0, 1.0])


def test_the_rendered_cache_stays_within_its_bytes() -> None:
    cache = RenderedCache(max_bytes=1000, max_item_bytes=600)
    for i in range(10):
        cache.put(f"k{i}", bytes(300))
    assert cache.size_bytes <= 1000 and len(cache) == 3
    assert cache.get("k0") is None and cache.get("k9") is not None  # oldest dropped
    cache.put("big", bytes(700))
    assert cache.get("big") is None  # larger than one item may be: sent, not kept
    drawn = []
    assert cache.get_or_render("new", lambda: drawn.append(1) or b"x") == b"x"
    assert cache.get_or_render("new", lambda: drawn.append(1) or b"y") == b"x"
    assert drawn == [1]
