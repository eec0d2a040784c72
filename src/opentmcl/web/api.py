"""The JSON API's plumbing, shared by every route module of the dashboard (web/app.py, web/tools.py):
the request body (a JSON object, its typed fields) and the answer (`json_api`: the result as JSON,
the caller's mistakes as HTTP 400 {"error": "<one line>"}, too many long requests as 503)."""
from __future__ import annotations

import json
from collections.abc import Awaitable, Callable

from starlette.requests import Request
from starlette.responses import JSONResponse, Response

from .lanes import Busy
from .service import DashboardError

Json = dict[str, object]
ApiHandler = Callable[[Request], Awaitable[object]]   # returns the JSON answer, None for {"ok": true}
Endpoint = Callable[[Request], Awaitable[Response]]


class BadRequest(ValueError):
    pass


# --- the request body ------------------------------------------------------------------------

async def body(request: Request) -> Json:
    # Only JSON: a cross-site page cannot send it without a CORS preflight, which is never granted,
    # so another web site open in the same browser cannot drive the motors (CSRF).
    if request.headers.get("content-type", "").split(";")[0].strip().lower() != "application/json":
        raise BadRequest("requests must be JSON (Content-Type: application/json)")
    try:
        data = await request.json()
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise BadRequest("request body is not JSON") from None
    if not isinstance(data, dict):
        raise BadRequest("request body must be a JSON object")
    return data


def one_line(text: str, limit: int = 200) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[:limit] + "..."


def int_field(data: Json, key: str) -> int:
    """`data[key]` as an integer: a JSON number or a string in Python's literal syntax (0x10)."""
    value = data.get(key)
    if isinstance(value, str):
        try:
            value = int(value.strip(), 0)
        except ValueError:
            raise BadRequest(f"{key} must be an integer, got {value!r}") from None
    if isinstance(value, bool) or not isinstance(value, int):
        raise BadRequest(f"{key} must be an integer, got {value!r}")
    return value


def optional_int(data: Json, key: str) -> int | None:
    """Like `int_field`, but a missing key or null is None."""
    return None if data.get(key) is None else int_field(data, key)


def number_field(data: Json, key: str, default: float) -> float:
    """`data[key]` as a finite number of seconds (a JSON number), `default` when missing."""
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value:
        raise BadRequest(f"{key} must be a number, got {value!r}")
    return float(value)


def str_field(data: Json, key: str) -> str:
    value = data.get(key)
    if not isinstance(value, str):
        raise BadRequest(f"{key} must be a string")
    return value


def line_numbers(data: Json, key: str) -> list[int]:
    value = data.get(key)
    if not isinstance(value, list) or not all(isinstance(x, int) and not isinstance(x, bool) for x in value):
        raise BadRequest(f"{key} must be a list of line numbers")
    return value


# --- answers ---------------------------------------------------------------------------------

def json_api(handler: ApiHandler) -> Endpoint:
    """An endpoint answering `handler`'s result as JSON; the caller's mistakes are a 400 with
    {"error": "<one line>"}, too many long requests at once a 503 (web/lanes.py)."""
    async def endpoint(request: Request) -> Response:
        try:
            result = await handler(request)
        except Busy as exc:
            return JSONResponse({"error": str(exc)}, status_code=503, headers={"Retry-After": "1"})
        except (BadRequest, DashboardError) as exc:
            return JSONResponse({"error": str(exc)}, status_code=400)
        except ValueError as exc:  # e.g. a number literal too long to convert: still the input's fault
            return JSONResponse({"error": one_line(f"bad request: {exc}")}, status_code=400)
        except RecursionError:
            return JSONResponse({"error": "bad request: input nested too deeply"}, status_code=400)
        return JSONResponse(result if result is not None else {"ok": True})
    endpoint.__name__ = getattr(handler, "__name__", "endpoint")  # the route's name
    return endpoint
