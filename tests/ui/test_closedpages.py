"""A page closed mid-send leaves no traceback in the server's output; other errors still show."""

import asyncio
import logging

import pytest

pytest.importorskip("aiohttp")
from aiohttp.client_exceptions import ClientConnectionResetError  # noqa: E402
from vidcap.ui import closedpages  # noqa: E402


async def _fail(exc: BaseException) -> None:
    raise exc


def _run_unretrieved(exc: BaseException) -> None:
    """Let a task fail with ``exc`` and be forgotten, as wslink's send task is."""

    async def main():
        closedpages.quiet_closed_pages()
        task = asyncio.get_running_loop().create_task(_fail(exc))
        await asyncio.sleep(0.01)
        assert task.done()
        del task

    asyncio.run(main())


@pytest.mark.parametrize("exc", [ClientConnectionResetError("Cannot write to closing transport"),
                                 BrokenPipeError(32, "Broken pipe"),
                                 ConnectionAbortedError(103, "Software caused connection abort")])
def test_closed_page_is_quiet(caplog, exc):
    with caplog.at_level(logging.ERROR, logger="asyncio"):
        _run_unretrieved(exc)
        import gc

        gc.collect()
    assert "Traceback" not in caplog.text and "never retrieved" not in caplog.text


def test_other_errors_still_reported(caplog):
    with caplog.at_level(logging.ERROR, logger="asyncio"):
        _run_unretrieved(ValueError("a real bug"))
        import gc

        gc.collect()
    assert "never retrieved" in caplog.text and "a real bug" in caplog.text


def test_outside_a_loop_does_nothing():
    closedpages.quiet_closed_pages()  # no running loop: no error, no handler installed
