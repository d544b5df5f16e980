"""Shared fixtures: registries with the built-in and toy plugins, graphs, caches, and a
real browser (Debian's Chromium driven by Playwright; nothing downloads one)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

import graphvision as gv

FIXTURES = Path(__file__).parent / "fixtures"
TOY = FIXTURES / "toy.py"
PIPELINES = Path(__file__).parent.parent / "pipelines"
CHROMIUM = next(
    (shutil.which(name) for name in ("chromium", "chromium-browser") if shutil.which(name)), None
)


@pytest.fixture(scope="module")
def browser() -> Iterator[object]:
    """The installed Chromium, launched once per test module; the test is skipped, with
    the reason, when Playwright or Chromium is missing (CI installs both)."""
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    if CHROMIUM is None:
        pytest.skip("no Chromium installed (CI installs one)")
    with sync_api.sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield launched
        launched.close()


@pytest.fixture(scope="session")
def registry() -> gv.Registry:
    """Installed plugins plus the toy plugin."""
    found = gv.discover([TOY])
    assert not found.failed_plugins(), found.failed_plugins()
    return found


@pytest.fixture
def cache(tmp_path: Path) -> gv.Cache:
    return gv.Cache(gv.MemoryStore(), gv.DiskStore(tmp_path / "cache"))


@pytest.fixture(autouse=True)
def isolated_cache_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The CLI's default disk cache goes to a per-test folder."""
    monkeypatch.setenv("GRAPHVISION_CACHE_DIR", str(tmp_path / "default-cache"))


@pytest.fixture(autouse=True)
def restored_run_limits() -> Iterator[None]:
    """Limits the command line hands to a run through the environment (``--max-pixels``,
    ``--max-memory``, ``--node-timeout``, ``--node-memory``) end with the test that set them."""
    names = [
        "GRAPHVISION_MAX_PIXELS",
        "GRAPHVISION_MAX_MEMORY",
        "GRAPHVISION_NODE_TIMEOUT",
        "GRAPHVISION_NODE_MEMORY",
    ]
    saved = {name: os.environ.get(name) for name in names}
    yield
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def pytest_configure(config: pytest.Config) -> None:
    """One line per test file as it completes (see ``tests/file_summary.py``)."""
    from .file_summary import FileSummary

    config.pluginmanager.register(FileSummary(config), "graphvision-file-summary")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked ``heavy`` (tens of seconds each) run first, the rest in their order.

    ``make test`` shares the tests between two workers that steal from each other
    (``--dist worksteal``): with the longest started first, the two finish together,
    instead of one worker running a pipeline test for a minute after the other stopped.
    """
    items.sort(key=lambda item: item.get_closest_marker("heavy") is None)


@pytest.fixture(scope="session")
def s3_options():
    """An S3-compatible server (moto's, in a thread of this process) and the fsspec options
    that reach it: a bucket ``gv-tests`` to put stores in. Skipped without moto and s3fs."""
    pytest.importorskip("s3fs", reason="the S3 store's tests need s3fs (graphvision[dev])")
    server_module = pytest.importorskip("moto.server", reason="needs moto[server] (dev extra)")
    server = server_module.ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    host, port = server.get_host_and_port()
    options = {
        "key": "testing",
        "secret": "testing",
        "client_kwargs": {"endpoint_url": f"http://{host}:{port}", "region_name": "us-east-1"},
    }
    import boto3

    boto3.client(
        "s3",
        aws_access_key_id="testing",
        aws_secret_access_key="testing",
        **options["client_kwargs"],
    ).create_bucket(Bucket="gv-tests")
    yield options
    server.stop()
