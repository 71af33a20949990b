# SPDX-License-Identifier: GPL-3.0-or-later
"""gridshell_client: a standard-library-only Python client of gridshelld's HTTP/JSON API.

    from gridshell_client import Client, Cancel, mesh_file
    client = Client("http://127.0.0.1:8080")             # token=, ca_file=, timeout= as needed
    design = client.design(mesh_file("vault.obj"), corners=[0, 40, 1680, 1640],
                           options={"alpha": "max"}, progress=lambda p: print(p.stage, p.fraction))
    deployment = client.simulate(design["design"], options={"unit": "cm"})
    print(deployment["deployment"]["rms_with_notches"])

The daemon describes every request option (type, default, range, help) and its materials:
``Description(client.options())`` (options.py) looks them up, ``describe(client)`` keeps the
description per daemon.

Used by the Blender add-on (client/blender) and the FreeCAD workbench (client/freecad); see
docs/api.md ("Python client").
"""

from .client import Cancel, Client, Progress, RawJSON, files_of
from .errors import (
    Cancelled,
    DeadlineExceeded,
    GridshellError,
    Infeasible,
    InternalError,
    InvalidInput,
    ResourceExhausted,
    Unauthenticated,
    Unavailable,
)
from .meshes import mesh_arrays, mesh_example, mesh_file
from .options import Description, describe
from . import options, plugin  # noqa: E402 (the description's helpers; helpers of the CAD plugins)

__version__ = "0.1.0"

__all__ = [
    "Client",
    "Cancel",
    "Progress",
    "RawJSON",
    "files_of",
    "mesh_arrays",
    "mesh_file",
    "mesh_example",
    "Description",
    "describe",
    "GridshellError",
    "InvalidInput",
    "Infeasible",
    "Cancelled",
    "DeadlineExceeded",
    "Unavailable",
    "Unauthenticated",
    "ResourceExhausted",
    "InternalError",
]
