"""The planner page end to end in a real headless browser (Debian's chromium and
chromedriver, driven by selenium): load the page, sort and filter the fleet table, open a
wheel and a plan, and compare what the page shows with the API's answers.

Skips, saying so, when selenium, chromium or chromedriver is absent
(``apt-get install -y chromium chromium-driver``; selenium is a dev dependency).
"""

from __future__ import annotations

import datetime as dt
import os
import shutil
import socket
import threading
import time
import warnings

import httpx
import pytest

from wearcast.service.app import create_app
from wearcast.service.settings import Settings
from wearcast.statistics.maintenance.synthetic import generate_fleet

TODAY = dt.date(2026, 6, 1)
#: The suite's admin key (tests/conftest.py sets WEARCAST_API_KEY for every app it builds).
KEY = os.environ["WEARCAST_API_KEY"]
AUTH = {"Authorization": f"Bearer {KEY}"}
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run")


def _browser_or_skip():
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        pytest.skip("selenium is not installed (pip install -e '.[dev]')")
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if chromium is None or driver is None:
        pytest.skip("chromium/chromedriver not found (apt-get install -y chromium "
                    "chromium-driver)")
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in FLAGS:
        options.add_argument(flag)
    options.add_argument("--window-size=1400,1000")
    return webdriver.Chrome(service=Service(driver), options=options)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    import uvicorn

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        app = create_app(Settings(data_dir=tmp_path_factory.mktemp("browser")))
    port = _free_port()
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning")
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    base = f"http://127.0.0.1:{port}"
    for _ in range(200):
        try:
            if httpx.get(base + "/v1/health").status_code == 200:
                break
        except httpx.HTTPError:
            time.sleep(0.05)
    fleet = generate_fleet(2, seed=11, today=TODAY)
    r = httpx.post(base + "/v1/measurements/import", headers=AUTH,
                   files={"file": ("fleet.csv", fleet.long_csv().encode())}, timeout=120)
    assert r.status_code == 200, r.text
    yield base
    srv.should_exit = True
    thread.join(timeout=10)


@pytest.fixture(scope="module")
def browser():
    driver = _browser_or_skip()
    yield driver
    driver.quit()


def _wait(browser, condition, timeout=20.0):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(browser, timeout).until(lambda d: condition(d))


_ROWS_JS = """
return Array.from(document.querySelectorAll('#fleet-table tbody tr')).map(tr => [
  tr.dataset.wheelId,
  Object.fromEntries(Array.from(tr.cells).map(td => [td.dataset.col, td.textContent])),
  tr.className]);
"""


def _rows(browser):
    """The fleet table as the page shows it: (wheel id, {column: text}, row class) per row,
    read in one script call."""
    return [tuple(r) for r in browser.execute_script(_ROWS_JS)]


def test_fleet_table_sort_filter_wheel_and_plan(server, browser):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    api = httpx.get(server + "/v1/fleet/state", params={"today": TODAY.isoformat()},
                    headers=AUTH).json()
    browser.get(f"{server}/planner/?today={TODAY.isoformat()}#key={KEY}")
    _wait(browser, lambda d: len(_rows(d)) == api["n_wheels"])
    by_id = {w["wheel_id"]: w for w in api["wheels"]}
    # what the page shows is what the API answered
    for wheel_id, cells, css in _rows(browser):
        w = by_id[wheel_id]
        assert cells["sd_mm"] == f"{w['sd_mm']:.2f}"
        assert cells["urgency"] == w["urgency"] and css == f"u-{w['urgency']}"
        assert cells["p10"] == f"{round(w['first_limit']['p10']):,}"
    # default order: P10 ascending; click P10 to reverse, Sd to sort by Sd
    p10 = [by_id[r[0]]["first_limit"]["p10"] for r in _rows(browser)]
    assert p10 == sorted(p10)
    browser.find_element(By.CSS_SELECTOR, 'th[data-sort="p10"]').click()
    p10 = [by_id[r[0]]["first_limit"]["p10"] for r in _rows(browser)]
    assert p10 == sorted(p10, reverse=True)
    browser.find_element(By.CSS_SELECTOR, 'th[data-sort="sd_mm"]').click()
    sd = [by_id[r[0]]["sd_mm"] for r in _rows(browser)]
    assert sd == sorted(sd)
    # filter by vehicle, then by urgency
    box = browser.find_element(By.ID, "filter")
    box.send_keys("V002")
    _wait(browser, lambda d: all(r[0].startswith("V002") for r in _rows(d)))
    assert len(_rows(browser)) == sum(w["vehicle_id"] == "V002" for w in api["wheels"])
    box.clear()
    box.send_keys(" ")  # an input event with an empty filter
    urgent = {w["urgency"] for w in api["wheels"]}
    chosen = sorted(urgent)[0]
    Select(browser.find_element(By.ID, "urgency-filter")).select_by_visible_text(chosen)
    _wait(browser, lambda d: {r[1]["urgency"] for r in _rows(d)} == {chosen})
    assert len(_rows(browser)) == sum(w["urgency"] == chosen for w in api["wheels"])
    Select(browser.find_element(By.ID, "urgency-filter")).select_by_visible_text("all")

    # open a wheel with an Sd history: its Sd points, forecast and limit are the API's
    wheel_id = next(r[0] for r in _rows(browser)
                    if by_id[r[0]]["remaining_km"]["sd"]["source"] == "history")
    browser.find_element(By.CSS_SELECTOR, f'tr[data-wheel-id="{wheel_id}"]').click()
    _wait(browser, lambda d: d.find_element(By.ID, "wheel-title").text == f"Wheel {wheel_id}")
    detail = httpx.get(server + f"/v1/fleet/wheels/{wheel_id}",
                       params={"today": TODAY.isoformat()}, headers=AUTH).json()
    points = browser.find_elements(By.CSS_SELECTOR, "#chart-sd circle.point")
    shown = sorted((float(p.get_attribute("data-mileage")), float(p.get_attribute("data-value")))
                   for p in points)
    expected = sorted((h["mileage_km"], h["sd_mm"]) for h in detail["history"])
    assert [v for pair in shown for v in pair] == pytest.approx(
        [v for pair in expected for v in pair])
    limit = browser.find_element(By.CSS_SELECTOR, "#chart-sd line.limit")
    assert float(limit.get_attribute("data-limit")) == detail["limits"]["sd_min_mm"]
    assert browser.find_elements(By.CSS_SELECTOR, '#chart-sd polyline[data-quantile="p50"]')
    measured = browser.find_element(By.CSS_SELECTOR, "#chart-profile polyline.measured")
    assert int(measured.get_attribute("data-points")) == len(detail["profile"]["y_mm"])
    assert browser.find_elements(By.CSS_SELECTOR,
                                 '#chart-profile polyline[data-target="S1002"]')
    targets = [tr.get_attribute("data-target") for tr in
               browser.find_elements(By.CSS_SELECTOR, "#turning-table tbody tr")]
    assert targets == [o["target"] for o in detail["turning"]["options"]]

    # compute a plan in the page; compare with the stored plan from the API
    for field, value in (("plan-start", "06/01/2026"), ("plan-capacity", "2"),
                         ("plan-weeks-n", "40"), ("plan-fixed", "60000")):
        box = browser.find_element(By.ID, field)
        box.clear()
        box.send_keys(value)
    browser.find_element(By.ID, "plan-run").click()
    _wait(browser, lambda d: d.find_element(By.ID, "plan-result").is_displayed())
    plans = httpx.get(server + "/v1/plans", headers=AUTH).json()
    plan = httpx.get(server + f"/v1/plans/{plans[-1]['id']}", headers=AUTH).json()
    assert plan["spec"]["capacity_per_week"] == 2 and plan["horizon_weeks"] == 40
    assert plan["start"] == TODAY.isoformat()
    rows = browser.find_elements(By.CSS_SELECTOR, "#plan-weeks tbody tr")
    expected_weeks = [w for w in plan["weeks"] if w["load"] > 0]
    assert [int(r.get_attribute("data-week")) for r in rows] == \
        [w["week"] for w in expected_weeks]
    for r, w in zip(rows, expected_weeks, strict=True):
        shown = r.find_element(By.CSS_SELECTOR, 'td[data-col="wheelsets"]').text
        assert shown == ", ".join(w["wheelsets"])
    sets = [r.get_attribute("data-wheelset") for r in
            browser.find_elements(By.CSS_SELECTOR, "#plan-wheelsets tbody tr")]
    assert sets == [w["wheelset"] for w in plan["wheelsets"]
                    if w["week"] is not None or w["at_risk"]]
    reasons = [r.find_element(By.CSS_SELECTOR, 'td[data-col="reason"]').text for r in
               browser.find_elements(By.CSS_SELECTOR, "#plan-wheelsets tbody tr")]
    assert reasons == [w["reason"] for w in plan["wheelsets"]
                       if w["week"] is not None or w["at_risk"]]
    href = browser.find_element(By.ID, "plan-export-csv").get_attribute("href")
    assert httpx.get(href, headers=AUTH).text.startswith("week,turn_date,wheelset")
    # reopen it from the stored-plan list
    Select(browser.find_element(By.ID, "plan-list")).select_by_value(str(plan["id"]))
    _wait(browser, lambda d: f"Plan {plan['id']}:" in d.find_element(By.ID,
                                                                    "plan-summary").text)


def test_planner_api_needs_the_key_the_page_sends(server):
    """Without a key the API answers 401 (the page asks for one); the static page is open."""
    assert httpx.get(server + "/v1/fleet/state").status_code == 401
    assert httpx.get(server + "/planner/").status_code == 200
