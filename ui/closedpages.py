"""Pages that close while the server writes to them are not errors.

When the user closes the tab (or reloads it) while the annotate server is still pushing
a frame, wslink's send task fails with a connection reset; asyncio would print that
unretrieved exception with a traceback into the user's terminal, as if something had
broken. Nothing has: the annotations are saved on every edit, not on send. So the
server's event loop drops those errors (:data:`CLOSED_PAGE_ERRORS`) and hands everything
else to the usual handler.
"""

from __future__ import annotations

import asyncio

#: What writing to a page the browser has closed raises, as the socket goes (aiohttp's
#: ``ClientConnectionResetError`` is a ``ConnectionResetError``).
CLOSED_PAGE_ERRORS = (ConnectionResetError, ConnectionAbortedError, BrokenPipeError)


def _is_closed_page(context: dict) -> bool:
    return isinstance(context.get("exception"), CLOSED_PAGE_ERRORS)


def quiet_closed_pages(loop: asyncio.AbstractEventLoop | None = None) -> None:
    """Make ``loop`` (default: the running one) drop errors from writing to closed pages.

    Parameters
    ----------
    loop : asyncio.AbstractEventLoop, optional
        The server's loop; when omitted and no loop is running, nothing is done.
    """
    if loop is None:
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:  # called outside the server (a script or a test)
            return
    previous = loop.get_exception_handler()

    def handler(lp: asyncio.AbstractEventLoop, context: dict) -> None:
        if _is_closed_page(context):
            return
        if previous is not None:
            previous(lp, context)
        else:
            lp.default_exception_handler(context)

    loop.set_exception_handler(handler)
