# SPDX-License-Identifier: GPL-3.0-or-later
"""The Python client (client/python/gridshell_client): the copy inside the installable zip, or,
when the workbench runs from the source tree, the one beside it there."""

import os
import sys

try:
    from . import gridshell_client as gs  # noqa: F401 (the zip built by scripts/build.sh)
except ImportError:
    _SOURCE = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", "..", "python"))
    if _SOURCE not in sys.path:
        sys.path.insert(0, _SOURCE)
    import gridshell_client as gs  # noqa: F401
