"""Run ezc3d on a file in a forked child, where a crash cannot take this process down.

:mod:`vidcap.mocap.c3dcheck` refuses the declared sizes ezc3d would choke on, but ezc3d
is a C++ parser that trusts its input in more places than a Python check can list (the
fuzz suite found a segmentation fault with every declared size in range). So the parse
runs in a child forked for it, under an address-space cap; only the parts of the result
vidcap uses come back (pickled through a pipe). A signal or an exhausted cap in the
child becomes one :class:`vidcap.errors.C3DError`. Where ``os.fork`` is missing the parse
runs in this process, after the checks.

Cost (benchmarks/fuzz.py's reference row; ``joints`` on 07_01.c3d): a fork and one
pickle of the point array, a few milliseconds against the parse's tens.
"""

from __future__ import annotations

import os
import pickle
import signal

from vidcap.errors import C3DError

#: Address space a parse may use beyond this process's, per byte of file (ezc3d keeps
#: objects of tens of bytes per stored value), plus a floor.
BYTES_PER_FILE_BYTE = 400
FLOOR_BYTES = 1 << 30


def _parse(path: str) -> dict:
    import ezc3d
    import numpy as np

    c = ezc3d.c3d(path, extract_forceplat_data=False)
    params = {g: {k: {"value": v["value"]} for k, v in grp.items()
                  if isinstance(v, dict) and "value" in v}
              for g, grp in c["parameters"].items() if isinstance(grp, dict)}
    meta = c["data"].get("meta_points", {})
    return {"parameters": params,
            "points": np.asarray(c["data"]["points"], dtype=float),
            "residuals": (np.asarray(meta["residuals"], dtype=float)
                          if "residuals" in meta else None),
            "header": {"frame_rate": float(c["header"]["points"]["frame_rate"]),
                       "first_frame": int(c["header"]["points"]["first_frame"])}}


def _reason(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def read_isolated(path) -> dict:
    """ezc3d's parse of ``path`` (every parameter's value, points (4, M, F), residuals,
    header).

    Raises
    ------
    C3DError
        ezc3d refused the file, crashed on it, or needed more memory than its size allows.
    """
    if not hasattr(os, "fork"):  # pragma: no cover - not POSIX
        try:
            return _parse(str(path))
        except Exception as exc:  # noqa: BLE001 - ezc3d raises plain errors
            raise C3DError(f"not a readable C3D file ({_reason(exc)})", path) from None
    import resource

    cap = FLOOR_BYTES + BYTES_PER_FILE_BYTE * os.path.getsize(path)
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: parse, send, leave without running any cleanup
        code = 0
        try:
            os.close(r)
            import faulthandler

            faulthandler.disable()  # a crash here is the answer, not news for the terminal
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 2)  # nor is what the parser prints on its way down
            soft, hard = resource.getrlimit(resource.RLIMIT_AS)
            mine = _address_space()
            limit = mine + cap if hard == resource.RLIM_INFINITY else min(hard, mine + cap)
            resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
            try:
                payload = (True, _parse(str(path)))
            except MemoryError:
                payload = (False, "the file declares more data than it can hold")
            except Exception as exc:  # noqa: BLE001 - ezc3d raises plain errors
                payload = (False, _reason(exc))
            with os.fdopen(w, "wb") as fh:
                pickle.dump(payload, fh, protocol=pickle.HIGHEST_PROTOCOL)
        except BaseException:  # noqa: BLE001 - nothing may escape a forked child
            code = 1
        finally:
            os._exit(code)
    os.close(w)
    try:
        with os.fdopen(r, "rb") as fh:
            data = fh.read()
    finally:
        _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        sig = os.WTERMSIG(status)
        name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else sig
        raise C3DError(f"not a readable C3D file (the C3D parser crashed on it: {name})",
                       path)
    try:
        ok, value = pickle.loads(data)
    except Exception:  # noqa: BLE001 - a child that died before it could answer
        raise C3DError("not a readable C3D file (the C3D parser stopped on it)", path) \
            from None
    if not ok:
        raise C3DError(f"not a readable C3D file ({value})", path)
    return value


def _address_space() -> int:
    """This process's virtual size in bytes (Linux ``/proc``; else 0)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError):
        return 0
