# SPDX-License-Identifier: GPL-3.0-or-later
"""The daemon's description of every request option and of its material presets (the ``Options``
method, ``POST /v1/options``: ``OptionsResult`` of proto/gridshell/v1/options.proto), so that a
client builds its choices, defaults and checks from it instead of keeping a copy of its own.

    from gridshell_client import Client, Description, describe
    client = Client("http://127.0.0.1:8080")
    description = Description(client.options())   # or describe(client): fetched once per daemon
    description.material_names()       # ["lime-wood", ..., "steel", "hdpe", the site's own]
    description.default_material        # "lime-wood": the first, the daemon's default
    option = description.option("design", "resolution")   # the OptionDescription dict
    description.default("design", "resolution")           # 100
    description.check("design", "resolution", 4)          # "expected 8 to 1000 or 0 (adaptive), got 4"
    description.check("design", "resolution", 0)          # None: allowed
    description.mesh_formats            # ["obj", "off", "ply", "stl"]

A site's own materials (``GRIDSHELL_MATERIALS`` of the daemon) are part of the description, after
the built-in ones (``site`` true). ``describe(client)`` keeps the description of each daemon
address for the process (the CAD plugins fetch it once and read it while drawing);
``cached(server)`` returns what was fetched, without a call.
"""

import math
import threading

__all__ = ["Description", "describe", "cached", "forget", "GROUPS", "TYPES"]

# The option groups of the description, in the order of a request's life (options.proto).
GROUPS = ("patch", "design", "simulation", "layout", "fabrication")
# The option types of the description.
TYPES = ("number", "integer", "boolean", "choice", "text", "numbers")

_CACHE = {}  # daemon address -> Description
_CACHE_LOCK = threading.Lock()


class Description:
    """An ``OptionsResult`` (the dict ``Client.options()`` returns) with look-ups.

    ``raw`` is the dict itself; ``options``, ``materials``, ``mesh_formats`` and ``length_units``
    its lists (empty when the answer lacks them).
    """

    def __init__(self, result):
        if isinstance(result, Description):
            result = result.raw
        if not isinstance(result, dict):
            raise TypeError("expected the OptionsResult dict, got %s" % type(result).__name__)
        self.raw = result
        self.options = [o for o in result.get("options", []) if isinstance(o, dict)]
        self.materials = [m for m in result.get("materials", []) if isinstance(m, dict)]
        self.mesh_formats = list(result.get("mesh_formats", []))
        self.length_units = list(result.get("length_units", []))
        self._index = {(o.get("group", ""), o.get("name", "")): o for o in self.options}

    def __repr__(self):
        return "Description(%d options, materials %s)" % (len(self.options), self.material_names())

    # ---- options ---------------------------------------------------------------------------

    def groups(self):
        """The groups the options belong to, in the description's order."""
        seen = []
        for option in self.options:
            if option.get("group") not in seen:
                seen.append(option.get("group"))
        return seen

    def group(self, group, outputs=False):
        """The options of one group (``"patch"``, ``"design"``, ``"simulation"``,
        ``"fabrication"``), without the results-only ones unless ``outputs``."""
        return [
            o
            for o in self.options
            if o.get("group") == group and (outputs or not o.get("output", False))
        ]

    def option(self, group, name):
        """The ``OptionDescription`` dict of option ``name`` (its proto field name) in ``group``,
        or None when the daemon does not describe it."""
        return self._index.get((group, name))

    def _require(self, group, name):
        option = self.option(group, name)
        if option is None:
            raise KeyError("the daemon describes no option %s.%s" % (group, name))
        return option

    def default(self, group, name):
        """The option's default as a Python value (a number, an int, a bool, a string, a list of
        numbers for ``numbers``), or None when it has none; KeyError for an unknown option."""
        return parse_value(self._require(group, name))

    def choices(self, group, name):
        """The values a ``choice`` option takes (a list; empty for other types)."""
        return list(self._require(group, name).get("choices", []))

    def check(self, group, name, value):
        """None when ``value`` is allowed for the option by its description (type, range,
        ``zero_allowed``, choices, count), else why not, in words (what the daemon's check
        would refuse; the daemon remains the authority: it also checks what the description
        words only, such as ``note``). KeyError for an unknown option."""
        return check_value(self._require(group, name), value)

    # ---- materials -------------------------------------------------------------------------

    def material_names(self):
        """The names the simulation's ``material`` takes: the built-in presets (the default
        first), then the site's own."""
        return [m.get("name", "") for m in self.materials]

    def material(self, name):
        """The ``MaterialPreset`` dict of ``name`` (moduli and strengths in Pa), or None."""
        for m in self.materials:
            if m.get("name") == name:
                return m
        return None

    @property
    def default_material(self):
        """The daemon's default material (the first of the description), or None."""
        return self.materials[0].get("name") if self.materials else None


def parse_value(option, text=None):
    """The option's ``default_value`` (or ``text``) as a Python value of its type; None for an
    empty text of a number, integer, boolean or numbers option."""
    text = option.get("default_value", "") if text is None else text
    kind = option.get("type", "")
    if kind in ("number", "integer", "boolean", "numbers") and text == "":
        return None
    if kind == "number":
        return float(text)
    if kind == "integer":
        number = float(text)
        return int(number) if number == int(number) else number
    if kind == "boolean":
        return text.strip().lower() == "true"
    if kind == "numbers":
        return [float(t) for t in text.split(",") if t.strip()]
    return text


def _text(x):
    """A number for a message: integers without a point, others with up to 15 digits."""
    x = float(x)
    if x == int(x) and abs(x) < 1e15:
        return "%d" % x
    return format(x, ".15g")


def _range_text(option):
    low, high = option.get("minimum"), option.get("maximum")
    if low is not None and high is not None:
        text = "%s%s to %s%s" % (
            _text(low),
            " (exclusive)" if option.get("exclusive_minimum") else "",
            _text(high),
            " (exclusive)" if option.get("exclusive_maximum") else "",
        )
    elif low is not None:
        text = ("above " if option.get("exclusive_minimum") else "at least ") + _text(low)
    elif high is not None:
        text = ("below " if option.get("exclusive_maximum") else "at most ") + _text(high)
    else:
        text = "a number"
    if option.get("zero_allowed"):
        text += " or 0" + (" (%s)" % option["zero_means"] if option.get("zero_means") else "")
    return text


def _number_problem(option, value, integer):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return "expected %s, got %r" % ("an integer" if integer else "a number", value)
    if not math.isfinite(value):
        return "expected a finite number, got %r" % (value,)
    if integer and value != int(value):
        return "expected an integer, got %r" % (value,)
    if value == 0 and option.get("zero_allowed"):
        return None
    low, high = option.get("minimum"), option.get("maximum")
    below = low is not None and (value <= low if option.get("exclusive_minimum") else value < low)
    above = high is not None and (value >= high if option.get("exclusive_maximum") else value > high)
    if below or above:
        return "expected %s, got %s" % (_range_text(option), _text(value))
    return None


def check_value(option, value):
    """None when ``value`` passes the ``OptionDescription`` ``option``, else why not."""
    kind = option.get("type", "")
    if kind == "number":
        return _number_problem(option, value, False)
    if kind == "integer":
        return _number_problem(option, value, True)
    if kind == "boolean":
        return None if isinstance(value, bool) else "expected true or false, got %r" % (value,)
    if kind == "choice":
        choices = list(option.get("choices", []))
        if value in choices:
            return None
        return "expected one of %s, got %r" % (", ".join(repr(c) for c in choices), value)
    if kind == "numbers":
        if not isinstance(value, (list, tuple)):
            return "expected a list of numbers, got %r" % (value,)
        count = option.get("count", 0)
        if count and len(value) != count:
            return "expected %d numbers, got %d" % (count, len(value))
        for k, item in enumerate(value):
            problem = _number_problem(option, item, False)
            if problem:
                return "[%d]: %s" % (k, problem)
        return None
    if kind == "text":
        return None if isinstance(value, str) else "expected text, got %r" % (value,)
    return None  # a type this client does not know: the daemon checks it


def _address(server):
    """The cache key of a daemon: a Client's address, or an address as a Client spells it."""
    from .client import Client  # here: client.py imports nothing of this module
    from .errors import GridshellError

    if isinstance(server, Client):
        return server.server + server._prefix
    try:
        client = Client(server)
    except GridshellError:
        return None
    return client.server + client._prefix


def describe(client, refresh=False, **call):
    """The ``Description`` of ``client``'s daemon: fetched with ``client.options(**call)`` the
    first time (or with ``refresh``), then kept for the process by the daemon's address."""
    key = _address(client)
    if not refresh:
        with _CACHE_LOCK:
            if key in _CACHE:
                return _CACHE[key]
    description = Description(client.options(**call))
    with _CACHE_LOCK:
        _CACHE[key] = description
    return description


def cached(server):
    """The ``Description`` fetched by ``describe`` for ``server`` (a Client or an address), or
    None when none was; never calls the daemon."""
    key = _address(server)
    if key is None:
        return None
    with _CACHE_LOCK:
        return _CACHE.get(key)


def forget(server=None):
    """Drops the kept description of ``server`` (a Client or an address), or all of them."""
    with _CACHE_LOCK:
        if server is None:
            _CACHE.clear()
        else:
            _CACHE.pop(_address(server), None)
