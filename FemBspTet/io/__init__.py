# SPDX-License-Identifier: LGPL-2.1-or-later
"""Files: the formats table (``formats``), surface and volume readers and writers with file:line
messages, named sets, atomic writes, CAD tessellation through FreeCAD's OpenCASCADE, pictures.
Imports only the kernel."""
