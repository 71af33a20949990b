# SPDX-License-Identifier: GPL-3.0-or-later
"""What the add-on takes from the daemon's description of its options and materials (the
``Options`` method, docs/api.md; ``gridshell_client.options``): the panel's material choices,
and the ranges against which the panel marks a design option red.

The description is read from the daemon the settings name (server, token, CA file): in the
background when the panel first draws with that server (again after a failed read once a call
to that daemon succeeded), or by the refresh button in the header of the panel's Simulation box
(``gridshell.refresh_options``, also for scripts). It is kept for the Blender session per daemon
address. Until it is there the material list holds one item, *Default*: the request
then names no material and the daemon takes its default. A material chosen earlier (kept in the
.blend file by name, ``material_name``) stays selected and is sent as it is even when the
daemon's description lacks it; the daemon then refuses it, naming ``material``.
"""

import bpy

from .remote import gs

DEFAULT = "DEFAULT"  # the item shown before the description is there: the daemon's default

# Blender keeps no copy of the strings of a dynamic enum's items: every list handed out is kept
# here, by (description, chosen material), for the session.
_ITEMS = {}
# Daemon address -> the background call fetching its description, or the error text of the
# last attempt (no new attempt from drawing then; Refresh tries again).
_FETCHES = {}


def _label(material):
    label = material.get("label") or material.get("name", "")
    return label[:1].upper() + label[1:]


def _tip(material):
    parts = ["E %.3g GPa, G %.3g GPa" % (material.get("young_modulus", 0) / 1e9,
                                         material.get("shear_modulus", 0) / 1e9)]
    strengths = [(what, material.get(key, 0)) for what, key in
                 (("bending", "bending_strength"), ("shear", "shear_strength"))]
    known = ["%s %.3g MPa" % (what, value / 1e6) for what, value in strengths if value]
    if known:
        parts.append("strength " + ", ".join(known))
    if material.get("site"):
        parts.append("the site's material library")
    if material.get("source"):
        parts.append(material["source"])
    return "; ".join(parts)


def description(settings):
    """The description of the settings' daemon kept for this session, or None."""
    return gs.options.cached(settings.server)


def material_items(settings, context=None):
    """The ``material`` enum's items: the daemon's materials (the default first, then the
    site's), or *Default* alone before the description is there; a chosen material that the
    description lacks is added at the end."""
    known = description(settings)
    chosen = settings.material_name
    key = (known, chosen)
    items = _ITEMS.get(key)
    if items is not None:
        return items
    if known is not None and known.materials:
        rows = [(m.get("name", ""), _label(m), _tip(m)) for m in known.materials]
    else:
        rows = [(DEFAULT, "Default", "The daemon's default material; its materials are listed once "
                 "the add-on has read its description (Refresh)")]
    if chosen and chosen not in [r[0] for r in rows]:
        rows.append((chosen, chosen, "Not in the daemon's description: sent as it is"))
    items = [(identifier, label, tip, number) for number, (identifier, label, tip) in enumerate(rows)]
    _ITEMS[key] = items
    return items


def get_material(settings):
    """The enum's value: the chosen material's item (none chosen: the first, the default)."""
    chosen = settings.material_name
    for identifier, _, _, number in material_items(settings):
        if identifier == chosen:
            return number
    return 0


def set_material(settings, value):
    for identifier, _, _, number in material_items(settings):
        if number == value:
            settings.material_name = "" if identifier == DEFAULT else identifier
            return


def fetch(settings, timeout=10.0):
    """The description of the settings' daemon, read now (blocking, no retries) and kept."""
    client = settings.client()
    client.retries = 0
    _FETCHES.pop(settings.server, None)
    return gs.describe(client, refresh=True, timeout=timeout)


def status(settings):
    """None when the description is there, else what the panel says about it."""
    if description(settings) is not None:
        return None
    state = _FETCHES.get(settings.server)
    if isinstance(state, str):
        return state
    return "reading the daemon's materials" if state is not None else "the daemon's materials: Refresh"


def ensure(settings):
    """Starts reading the description of the settings' daemon in the background, once per
    address (for the panel's draw: it never waits for the daemon)."""
    server = settings.server
    if description(settings) is not None or server in _FETCHES:
        return
    try:
        client = settings.client()
    except gs.GridshellError as e:
        _FETCHES[server] = "materials not read: %s" % e.message
        return
    client.retries = 0

    def work(progress, cancel):
        return gs.describe(client, refresh=True, cancel=cancel, timeout=10)

    _FETCHES[server] = gs.plugin.BackgroundCall(work)
    if not bpy.app.timers.is_registered(_poll):
        bpy.app.timers.register(_poll, first_interval=0.1)


def reached(server):
    """A call to ``server`` succeeded: a failed read of its description is tried again at the
    panel's next draw."""
    if isinstance(_FETCHES.get(server), str):
        del _FETCHES[server]


def _poll():
    """Timer: ends the finished background reads; redraws the sidebars when one came in."""
    pending, finished = False, False
    for server, state in list(_FETCHES.items()):
        if isinstance(state, str):
            continue
        if not state.done:
            pending = True
            continue
        try:
            state.result()
            del _FETCHES[server]
        except Exception as e:  # shown in the panel; Refresh tries again
            _FETCHES[server] = "materials not read: %s" % (
                e.message if isinstance(e, gs.GridshellError) else e
            )
        finished = True
    if finished:
        redraw()
    return 0.1 if pending else None


def redraw():
    """Redraws the sidebars of every 3D view (the material list changed)."""
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                for region in area.regions:
                    if region.type == "UI":
                        region.tag_redraw()


def forget():
    """Drops the kept item lists and read states (the add-on is unregistered)."""
    for state in _FETCHES.values():
        if not isinstance(state, str):
            state.cancel()
    _FETCHES.clear()
    _ITEMS.clear()
    if bpy.app.timers.is_registered(_poll):
        bpy.app.timers.unregister(_poll)
