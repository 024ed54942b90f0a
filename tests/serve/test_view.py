"""The live view in a real headless Chromium (Debian's chromium and chromium-driver, driven by
selenium): the page loads a plan, draws every robot, the time slider moves them, and a state
posted to the service redraws the page with the revision, pushed as a server-sent event; in a
fleet of more than eight robots, robots that share a colour differ in their line."""

from __future__ import annotations

import itertools
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.serve.server import ROOT, Server
from tmpnav.client import Client
from tmpnav.report.figures import ROBOT_COLORS

CHROMIUM, DRIVER = Path("/usr/bin/chromium"), Path("/usr/bin/chromedriver")
webdriver = pytest.importorskip("selenium.webdriver", reason="the view's test needs selenium (the test extra)")
if not (CHROMIUM.exists() and DRIVER.exists()):
    pytest.skip(
        "Debian's chromium and chromium-driver are not installed (make test installs them as root: "
        "apt-get install chromium chromium-driver)",
        allow_module_level=True,
    )

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1200,900")  # fmt: skip


@pytest.fixture(scope="module")
def browser() -> Iterator[object]:
    profile = tempfile.mkdtemp(prefix="tmpnav-chromium-")
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (*FLAGS, f"--user-data-dir={profile}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(options=options, service=webdriver.ChromeService(executable_path=str(DRIVER)))
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def robots(driver: object) -> dict[str, tuple[float, float]]:
    """Each robot's drawn position, read in one script: the page redraws its list as the slider
    and the revisions move it, so elements found in one call may be gone by the next."""
    script = """
        const out = {};
        for (const li of document.querySelectorAll('#robots li'))
            if (li.dataset.x !== undefined) out[li.dataset.robot] = [Number(li.dataset.x), Number(li.dataset.y)];
        return out;"""
    found = driver.execute_script(script)  # type: ignore[attr-defined]
    return {name: (float(x), float(y)) for name, (x, y) in found.items()}


def painted(driver: object, colour: tuple[int, int, int]) -> int:
    """How many pixels of the map's canvas are ``colour``."""
    script = """
        const [r, g, b] = arguments[0], c = document.getElementById('map');
        const data = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let i = 0; i < data.length; i += 4)
            if (Math.abs(data[i] - r) < 8 && Math.abs(data[i + 1] - g) < 8 && Math.abs(data[i + 2] - b) < 8) n++;
        return n;"""
    return int(driver.execute_script(script, list(colour)))  # type: ignore[attr-defined]


def test_the_view_draws_the_plan_moves_the_robots_and_shows_revisions(
    server: Server, client: Client, first: dict, browser: object
) -> None:
    wait = WebDriverWait(browser, 120)
    browser.get(f"{server.url}/?plan={first['id']}")  # type: ignore[attr-defined]
    wait.until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-drawn") == "0")
    start = robots(browser)
    assert set(start) == set(first["robots"])
    assert painted(browser, (0x1F, 0x77, 0xB4)) > 50 and painted(browser, (0x2C, 0xA0, 0x2C)) > 50  # r1, r2
    slider = browser.find_element(By.ID, "time")  # type: ignore[attr-defined]
    slider.send_keys(Keys.END)  # the end of the schedule
    wait.until(lambda d: robots(d) != start)
    end = robots(browser)
    assert all(abs(end[r][0] - start[r][0]) + abs(end[r][1] - start[r][1]) > 1.0 for r in start)
    assert browser.find_element(By.ID, "clock").text == f"{first['makespan']:.1f} s"  # type: ignore[attr-defined]
    revised = client.post_state(first["id"], first["revision"], {"time": 10.0, "robots": {"r2": {"status": "down"}}})
    wait.until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-drawn") == str(revised["revision"]))
    assert browser.find_element(By.ID, "revision").text == str(revised["revision"])  # type: ignore[attr-defined]
    assert f"revision {revised['revision']}" in browser.find_element(By.ID, "summary").text  # type: ignore[attr-defined]


#: ten robots on configs/two-rooms.yaml's site, r3-r8 in a row in C: r1 drives to B, r9 (r1's
#: colour, from C's east end) to A, the others stay where they are
FLEET = ((3.0, 6.0, -1.5708), (11.0, 7.2, -1.5708), *((1.0 + 1.6 * i, 1.0, 0.0) for i in range(6)),
         (11.0, 1.0, 3.1416), (1.0, 3.0, 0.0))  # fmt: skip


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    folder = tmp_path_factory.mktemp("serve-fleet")
    site = (ROOT / "configs" / "two-rooms.yaml").read_text().split("\nrobots:")[0]
    robots = "".join(f"\n  - {{name: r{k}, pose: [{x:g}, {y:g}, {th:g}]}}" for k, (x, y, th) in enumerate(FLEET, 1))
    roadmap = "\nroadmap: {samples: 300, instantiations: 3, seed: 1}"
    (folder / "fleet.yaml").write_text(f"{site}\nrobots:{robots}{roadmap}\ngoals:\n  robots: {{r1: [B], r9: [A]}}\n")
    running = Server(str(folder / "fleet.yaml"), folder)
    try:
        yield running
    finally:
        running.stop()


def strokes(driver: object) -> list[tuple[str, str]]:
    """The colour and dash pattern of every line the map's canvas strokes in one redraw."""
    script = """
        const seen = [], proto = CanvasRenderingContext2D.prototype, stroke = proto.stroke;
        proto.stroke = function (...args) {
            if (this.canvas.id === 'map') seen.push([String(this.strokeStyle), this.getLineDash().join(' ')]);
            return stroke.apply(this, args);
        };
        try { draw(); } finally { proto.stroke = stroke; }
        return seen;"""
    return [(colour, dash) for colour, dash in driver.execute_script(script)]  # type: ignore[attr-defined]


def test_a_fleet_s_robots_that_share_a_colour_differ_in_their_line(fleet: Server, browser: object) -> None:
    plan = Client(fleet.url, timeout=600).plan()
    browser.get(f"{fleet.url}/?plan={plan['id']}")  # type: ignore[attr-defined]
    WebDriverWait(browser, 120).until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-drawn") == "0")
    script = """
        const out = {};
        for (const li of document.querySelectorAll('#robots li')) {
            const line = li.querySelector('svg line');
            out[li.dataset.robot] = {
                colour: li.dataset.colour, dash: li.dataset.dash, dot: getComputedStyle(li, '::before').color,
                swatch: line && [line.getAttribute('stroke'), line.getAttribute('stroke-dasharray')],
            };
        }
        return out;"""
    legend = browser.execute_script(script)  # type: ignore[attr-defined]
    assert len(legend) == 10
    r1, r9 = legend["r1"], legend["r9"]
    # r1 as in plan.png: blue, solid, the list's dot and no line
    assert r1 == {"colour": "#1f77b4", "dash": "", "dot": "rgb(31, 119, 180)", "swatch": None}
    assert [legend[f"r{k}"]["colour"] for k in range(1, 9)] == list(ROBOT_COLORS)
    assert all(legend[f"r{k}"]["dash"] == "" for k in range(1, 9))
    # r9: r1's colour, a dash of its own, in the list as a line after the dot
    assert r9["colour"] == r1["colour"] and r9["dot"] == r1["dot"] and r9["dash"] != ""
    assert r9["swatch"] == [r1["colour"], r9["dash"]]
    assert legend["r10"]["colour"] == legend["r2"]["colour"] and legend["r10"]["dash"] == r9["dash"]
    # on the map: r1's path and ellipses solid, r9's in its dash, a dashed ring around r9's disc
    drawn = strokes(browser)
    assert {dash for colour, dash in drawn if colour == r1["colour"]} == {"", r9["dash"]}
    assert ("#000000", r9["dash"]) in drawn
    assert painted(browser, (0x1F, 0x77, 0xB4)) > 50


def test_the_schedule_chart_grows_to_give_each_robot_of_a_fleet_a_readable_row(fleet: Server, browser: object) -> None:
    plan = Client(fleet.url, timeout=600).plan()
    browser.get(f"{fleet.url}/?plan={plan['id']}")  # type: ignore[attr-defined]
    WebDriverWait(browser, 120).until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-drawn") == "0")
    script = """
        const robots = view.plan.schedule.robots, names = Object.keys(robots), chart = document.getElementById('gantt');
        const labels = (n) => {
            for (let k = names.length + 1; k <= n; k++) robots['r' + k] = robots[names[(k - 1) % names.length]];
            const ys = {}, proto = CanvasRenderingContext2D.prototype, fill = proto.fillText;
            proto.fillText = function (text, x, y, ...rest) {
                if (this.canvas.id === 'gantt' && x === 6) ys[text] = y;
                return fill.call(this, text, x, y, ...rest);
            };
            try { drawGantt(); } finally { proto.fillText = fill; }
            return [chart.height, ys];
        };
        return [labels(names.length), labels(32)];"""
    (ten_height, ten), (height, labels) = browser.execute_script(script)  # type: ignore[attr-defined]
    assert 160 <= ten_height < 200 and len(ten) == 10  # about the page's chart for ten
    assert len(labels) == 32 and height >= 32 * 14 + 20
    ys = [labels[f"r{k}"] for k in range(1, 33)]
    assert all(b - a >= 14 - 1e-9 for a, b in itertools.pairwise(ys))  # rows one label high at least
    assert ys[-1] <= height - 20  # the last row above the time axis
