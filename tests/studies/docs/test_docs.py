"""The documentation site builds with warnings as errors, and its journeys ran.

The site is built once (``wheelload.studies.docs.build_docs``, as ``wheelload docs``), which
runs every journey's commands and programs: a command that fails stops the build. The
tests then read what the pages show: the outputs the journeys printed, checked against the
tolerances the library promises (the C example equals Python to 1e-9 N; the Dask cluster's
summary equals the local processes' to 1e-9). A headless Chromium with no network opens
pages of the built site from disk and shows every equation typeset by the MathJax the site
carries.
"""

import html
import re
import shutil
import subprocess

import pytest
from sphinx.errors import ExtensionError

from wheelload.studies.docs.build import DocsBuildError, build_docs
from wheelload.studies.docs.reference import CONTRACT, packages
from wheelload.studies.docs.run_blocks import run_block

pytestmark = [pytest.mark.heavy(77), pytest.mark.filterwarnings("ignore::DeprecationWarning")]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("site") / "html"
    index = build_docs(out, jobs=2)
    assert index == out / "index.html"
    return out


def _text(page) -> str:
    """A page's text: tags removed, entities decoded."""
    return html.unescape(re.sub(r"<[^>]+>", "", page.read_text()))


def _number(site, page: str, pattern: str) -> float:
    found = re.search(pattern, _text(site / page), re.MULTILINE)
    assert found, f"{page}: no line matching {pattern!r}"
    return float(found.group(1))


def test_every_package_has_a_reference_page_with_rendered_math(site):
    for package in packages():
        assert (site / "reference" / f"{package}.html").is_file(), package
    models = (site / "reference" / "wheelload.models.suspension.html").read_text()
    assert 'class="math' in models  # the docstrings' .. math:: reach MathJax
    assert "wheelload.models.suspension.elements.damper_force" in models


#: A headless Chromium (Debian's package; .ci/run installs it where apt-get works) with no
#: network: every host resolves to nothing and every request goes to a closed proxy. The
#: virtual time budget lets MathJax typeset before the DOM is dumped.
CHROMIUM = next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)
OFFLINE = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--proxy-server=http://127.0.0.1:9",
    "--host-resolver-rules=MAP * ~NOTFOUND",
    "--virtual-time-budget=30000",
)
#: An equation as Sphinx writes it (``\(...\)`` inline, ``\[...\]`` displayed), and as
#: MathJax leaves it once typeset.
MATH = re.compile(r'<(span|div) class="math notranslate nohighlight">(.*?)</\1>', re.DOTALL)
TYPESET = re.compile(r"<mjx-container[ >].*?</mjx-container>", re.DOTALL)


def _rendered(page, profile) -> str:
    """The page's DOM after a headless Chromium with no network has run its scripts."""
    command = [CHROMIUM, *OFFLINE, f"--user-data-dir={profile}", "--dump-dom", page.as_uri()]
    done = subprocess.run(command, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.mark.skipif(CHROMIUM is None, reason="no chromium: apt-get install chromium (.ci/run does)")
@pytest.mark.parametrize(
    "page", ["reference/contract.html", "reference/wheelload.models.suspension.html"]
)
def test_every_equation_is_typeset_without_a_network(site, page, tmp_path):
    """Each equation of the page becomes one MathJax container and no raw TeX is left."""
    written = (site / page).read_text()
    equations = [body for _, body in MATH.findall(written)]
    assert equations and all(body.strip().startswith(("\\(", "\\[")) for body in equations)
    dom = _rendered(site / page, tmp_path / "profile")
    assert len(TYPESET.findall(dom)) == len(equations)
    left = [body for _, body in MATH.findall(TYPESET.sub("", dom)) if body.strip()]
    assert left == []  # no \( or \[ left in the rendered equations


def test_the_reference_opens_with_the_contract(site):
    """The contract page lists every name of the faces, in their own namespace, and the
    internals do not describe those objects again."""
    index = _text(site / "reference" / "index.html")
    assert index.index("The contract") < index.index("Internals")
    contract = (site / "reference" / "contract.html").read_text()
    for face, groups in CONTRACT.items():
        for _, names in groups:
            for name in names:
                assert f'id="{face}.{name}"' in contract, f"{face}.{name}"
    registry = (site / "reference" / "wheelload.estimators.html").read_text()
    assert 'id="wheelload.estimators.registry.build"' not in registry
    assert 'id="wheelload-estimators-registry"' in registry  # the module's other members


def test_the_journeys_are_pages_of_the_site(site):
    index = (site / "index.html").read_text()
    journeys = ("own-car", "identify-tune", "compare", "c-on-an-ecu", "fmu", "fleets", "studies")
    for journey in journeys:
        assert (site / "journeys" / f"{journey}.html").is_file()
        assert f"journeys/{journey}.html" in index


def test_the_c_example_equals_python_on_the_bundled_log(site):
    """Tolerance 1e-9 N: the library promises 1e-9 relative on loads of about 5 kN."""
    page = "journeys/c-on-an-ecu.html"
    difference = _number(site, page, r"four loads: ([0-9.e+-]+) N$")
    assert difference < 1e-9
    assert "status bits equal on every sample: True" in _text(site / page)


def test_the_fmu_equals_python_on_a_lane_change(site):
    """Tolerance 1e-9 N, as the C library's (tests/estimators/codegen/test_fmu.py); the tunable
    spring reached the filter."""
    page = "journeys/fmu.html"
    for group in ("fz", "fx", "fy"):
        assert _number(site, page, rf"^{group}: .* wheels: ([0-9.e+-]+) N$") < 1e-9
    assert "status bits equal on every sample: True" in _text(site / page)
    assert _number(site, page, r"front left moves by up to ([0-9.]+) N$") > 1.0


def test_dask_and_local_processes_give_the_same_fleet_summary(site):
    page = "journeys/fleets.html"
    text = _text(site / page)
    assert "same logs in the same order: True; empty cells in the same places: True" in text
    assert _number(site, page, r"summaries' numbers: ([0-9.e+-]+)$") < 1e-9


def test_own_car_journey_reads_the_logger_file_through_its_map(site):
    """The MF4 with logger names, units and signs gives the bundled log's accuracy (< 35 N
    pooled RMSE; README's example gives 27.8 N on the plant's own log)."""
    page = "journeys/own-car.html"
    assert _number(site, page, r"^\s+POOLED\s+([0-9.]+)") < 35.0
    assert (site / "_images" / "loads.png").is_file()


def test_a_non_empty_folder_is_refused_without_force(tmp_path):
    (tmp_path / "keep.txt").write_text("the user's")
    with pytest.raises(DocsBuildError, match="not empty: give --force"):
        build_docs(tmp_path)
    assert (tmp_path / "keep.txt").read_text() == "the user's"


def test_a_failing_block_stops_the_build(tmp_path):
    assert run_block("shell", "echo fine", tmp_path) == "fine\n"
    with pytest.raises(ExtensionError, match="exit 3"):
        run_block("shell", "echo broken; exit 3", tmp_path)
