"""The annotate server is the user's alone: loopback only, this run's token, its own
Host and Origin; everything else is refused with 403 before a websocket upgrade."""

from __future__ import annotations

import asyncio
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("trame")
pytest.importorskip("trame_pyvista")
aiohttp = pytest.importorskip("aiohttp")

from vidcap.ui import access  # noqa: E402

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
SERVE = f"""
import sys
sys.path.insert(0, {str(HERE)!r})
from clips import truth_clip
from vidcap.ui.annotate import serve
from vidcap.ui.session import AnnotateSession
serve(AnnotateSession(truth_clip("walk_side"), sys.argv[1]), open_browser=False)
"""


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """(url, port, token) of a running annotate server; killed afterwards."""
    ann = tmp_path_factory.mktemp("access") / "a.json"
    proc = subprocess.Popen([sys.executable, "-c", SERVE, str(ann)], cwd=REPO,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        t0, line = time.monotonic(), ""
        while "http://" not in line:
            line = proc.stdout.readline()
            if not line and proc.poll() is not None or time.monotonic() - t0 > 120:
                pytest.fail(f"annotate server did not start ({proc.poll()})")
        url = re.search(r"http://\S+", line).group(0)
        m = re.fullmatch(r"http://127\.0\.0\.1:(\d+)/index\.html\?secret=([\w-]+)", url)
        assert m, url
        yield url, int(m.group(1)), m.group(2)
    finally:
        proc.kill()
        proc.wait(10)


def _ws_status(port: int, *, query: str = "", headers: dict | None = None,
               cookie: str | None = None) -> int:
    """HTTP status of a websocket upgrade to the server (101 when it was accepted)."""

    async def go():
        jar = aiohttp.CookieJar(unsafe=True)
        async with aiohttp.ClientSession(cookie_jar=jar) as http:
            if cookie:
                jar.update_cookies({access.cookie_name(port): cookie})
            try:
                async with http.ws_connect(f"http://127.0.0.1:{port}/ws{query}",
                                           headers=headers or {}):
                    return 101
            except aiohttp.WSServerHandshakeError as exc:
                return exc.status

    return asyncio.run(go())


def _get_status(url: str, headers: dict | None = None) -> tuple[int, dict]:
    async def go():
        async with aiohttp.ClientSession() as http:
            async with http.get(url, headers=headers or {}, allow_redirects=False) as r:
                return r.status, {k: v.value for k, v in r.cookies.items()}

    return asyncio.run(go())


def test_token_is_random_and_not_the_library_default():
    tokens = {access.new_token() for _ in range(20)}
    assert len(tokens) == 20 and "wslink-secret" not in tokens
    assert min(map(len, tokens)) >= 40


def test_the_page_needs_the_token_and_sets_a_strict_cookie(served):
    url, port, token = served
    status, cookies = _get_status(url)
    assert status == 200 and cookies == {access.cookie_name(port): token}
    assert _get_status(url.split("?")[0])[0] == 403
    assert _get_status(url.replace(token, token[:-1] + "x"))[0] == 403


def test_websocket_with_the_token_and_own_origin_is_accepted(served):
    _url, port, token = served
    own = {"Origin": f"http://127.0.0.1:{port}"}
    assert _ws_status(port, query=f"?secret={token}", headers=own) == 101
    assert _ws_status(port, headers=own, cookie=token) == 101


def test_websocket_without_the_token_is_refused(served):
    _url, port, token = served
    own = {"Origin": f"http://127.0.0.1:{port}"}
    assert _ws_status(port, headers=own) == 403
    assert _ws_status(port, headers=own, cookie="wslink-secret") == 403
    assert _ws_status(port, query="?secret=wslink-secret", headers=own) == 403


@pytest.mark.parametrize("origin", ["http://evil.example", "http://127.0.0.1:1", "null",
                                    "https://127.0.0.1:{port}"])
def test_websocket_from_a_foreign_origin_is_refused(served, origin):
    _url, port, token = served
    headers = {"Origin": origin.format(port=port)}
    assert _ws_status(port, query=f"?secret={token}", headers=headers) == 403
    assert _ws_status(port, headers=headers, cookie=token) == 403


@pytest.mark.parametrize("host", ["evil.example:{port}", "127.0.0.1.nip.io:{port}",
                                  "127.0.0.1:1"])
def test_websocket_with_a_foreign_host_is_refused(served, host):
    """DNS rebinding: a foreign name that resolves to 127.0.0.1 keeps its own Host."""
    _url, port, token = served
    host = host.format(port=port)
    headers = {"Host": host, "Origin": f"http://{host}"}
    assert _ws_status(port, query=f"?secret={token}", headers=headers) == 403
    assert _ws_status(port, query=f"?secret={token}", headers={"Host": host}) == 403


def test_listens_on_loopback_only(served):
    """Nothing answers on this machine's other addresses."""
    import socket

    _url, port, _token = served
    try:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.connect(("192.0.2.1", 9))  # no packet is sent: picks the outward interface
        outward = s.getsockname()[0]
        s.close()
    except OSError:
        pytest.skip("no network interface besides loopback")
    if outward.startswith("127."):
        pytest.skip("no network interface besides loopback")
    with pytest.raises(OSError):
        socket.create_connection((outward, port), 1).close()
