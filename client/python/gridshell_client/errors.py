# SPDX-License-Identifier: GPL-3.0-or-later
"""Errors of the gridshell HTTP API as Python exceptions.

Every failed call raises a GridshellError (or a subclass chosen by the gRPC status name the daemon
answers with). The exception carries the API's error body as data (docs/api.md, "Errors as
data"): ``status`` (``"INVALID_ARGUMENT"``, ``"FAILED_PRECONDITION"``, ...), ``code`` (the gRPC
code number), ``field`` (the request field it concerns, ``""`` for the whole call), ``message``
(plain text without the field) and ``http_status``; ``details`` is the whole ``error`` object as
the daemon sent it, so fields added to it later (ranked suggestions of an infeasible design)
reach the caller without a change here.
"""

__all__ = [
    "GridshellError",
    "InvalidInput",
    "Infeasible",
    "Cancelled",
    "DeadlineExceeded",
    "Unavailable",
    "Unauthenticated",
    "ResourceExhausted",
    "InternalError",
    "error_from_body",
]

# gRPC status names -> code numbers (google.rpc.Code), as the daemon reports them.
_CODES = {
    "OK": 0,
    "CANCELLED": 1,
    "UNKNOWN": 2,
    "INVALID_ARGUMENT": 3,
    "DEADLINE_EXCEEDED": 4,
    "NOT_FOUND": 5,
    "ALREADY_EXISTS": 6,
    "PERMISSION_DENIED": 7,
    "RESOURCE_EXHAUSTED": 8,
    "FAILED_PRECONDITION": 9,
    "ABORTED": 10,
    "OUT_OF_RANGE": 11,
    "UNIMPLEMENTED": 12,
    "INTERNAL": 13,
    "UNAVAILABLE": 14,
    "DATA_LOSS": 15,
    "UNAUTHENTICATED": 16,
}
_NAMES = {number: name for name, number in _CODES.items()}

# HTTP status -> gRPC status name, for answers without a JSON error body (a proxy's 503 page).
_HTTP_STATUS = {
    400: "INVALID_ARGUMENT",
    401: "UNAUTHENTICATED",
    403: "PERMISSION_DENIED",
    404: "NOT_FOUND",
    405: "UNIMPLEMENTED",
    413: "RESOURCE_EXHAUSTED",
    422: "FAILED_PRECONDITION",
    429: "RESOURCE_EXHAUSTED",
    499: "CANCELLED",
    501: "UNIMPLEMENTED",
    502: "UNAVAILABLE",
    503: "UNAVAILABLE",
    504: "DEADLINE_EXCEEDED",
}


# gRPC status name -> the HTTP status the gateway answers it with (docs/api.md, Status codes),
# for errors that arrive inside an event stream (whose HTTP status was already 200).
_STATUS_HTTP = {
    "INVALID_ARGUMENT": 400,
    "OUT_OF_RANGE": 400,
    "FAILED_PRECONDITION": 422,
    "CANCELLED": 499,
    "DEADLINE_EXCEEDED": 504,
    "RESOURCE_EXHAUSTED": 429,
    "UNAUTHENTICATED": 401,
    "PERMISSION_DENIED": 403,
    "NOT_FOUND": 404,
    "UNIMPLEMENTED": 501,
    "UNAVAILABLE": 503,
    "INTERNAL": 500,
}


class GridshellError(Exception):
    """A failed call: the daemon's error (status, field, message) or a transport failure."""

    def __init__(self, message, status="UNKNOWN", field="", http_status=0, details=None):
        self.status = status
        self.code = _CODES.get(status, 2)
        self.field = field or ""
        self.message = message
        self.http_status = http_status
        self.details = dict(details) if details else {}
        super().__init__(self.__str__())

    @property
    def suggestions(self):
        """Ranked suggestions the daemon attached to an infeasible design, if any (a list)."""
        value = self.details.get("suggestions")
        return list(value) if isinstance(value, list) else []

    def __str__(self):
        return "%s: %s" % (self.field, self.message) if self.field else self.message


class InvalidInput(GridshellError):
    """INVALID_ARGUMENT (HTTP 400): a bad mesh, corners, option, design or JSON."""


class Infeasible(GridshellError):
    """FAILED_PRECONDITION (HTTP 422): the design cannot be made (reflex corner, no feasible angle...)."""


class Cancelled(GridshellError):
    """The call was cancelled (by this client's Cancel, or the daemon reports CANCELLED)."""


class DeadlineExceeded(GridshellError):
    """The call's deadline passed (HTTP 504, or no answer in time)."""


class Unavailable(GridshellError):
    """The daemon cannot be reached, or is shutting down (HTTP 503)."""


class Unauthenticated(GridshellError):
    """A missing or wrong bearer token (HTTP 401)."""


class ResourceExhausted(GridshellError):
    """The daemon's queue is full (429) or the request body too large (413)."""


class InternalError(GridshellError):
    """A bug in the daemon (HTTP 500) or an answer this client cannot read."""


_CLASSES = {
    "INVALID_ARGUMENT": InvalidInput,
    "OUT_OF_RANGE": InvalidInput,
    "FAILED_PRECONDITION": Infeasible,
    "CANCELLED": Cancelled,
    "DEADLINE_EXCEEDED": DeadlineExceeded,
    "UNAVAILABLE": Unavailable,
    "UNAUTHENTICATED": Unauthenticated,
    "RESOURCE_EXHAUSTED": ResourceExhausted,
    "INTERNAL": InternalError,
}


def error_from_body(body, http_status=0):
    """The exception for an API error body ``{"error": {code, status, field, message, ...}}``.

    ``body`` is the parsed JSON (a dict) or None when the answer was not the API's JSON; the
    exception class follows the gRPC status name, else the HTTP status. ``http_status`` 0 (an
    error event of a stream) takes the status the gateway gives that error.
    """
    error = body.get("error") if isinstance(body, dict) else None
    if not isinstance(error, dict):
        status = _HTTP_STATUS.get(http_status, "INTERNAL" if http_status >= 500 else "UNKNOWN")
        return _CLASSES.get(status, GridshellError)(
            "HTTP %d without an API error body" % http_status, status, "", http_status
        )
    status = error.get("status")
    if not isinstance(status, str) or status not in _CODES:
        status = _NAMES.get(error.get("code"), _HTTP_STATUS.get(http_status, "UNKNOWN"))
    message = error.get("message")
    field = error.get("field")
    http_status = http_status or _STATUS_HTTP.get(status, 500)
    return _CLASSES.get(status, GridshellError)(
        message if isinstance(message, str) else "(no message)",
        status,
        field if isinstance(field, str) else "",
        http_status,
        error,
    )
