# SPDX-License-Identifier: LGPL-2.1-or-later
"""The ``fembsptet`` command line (``main``), its supervisor (time and memory limits, Ctrl-C) and
``freecad-install``. ``python3 -m FemBspTet.cli`` runs it. Imports everything but gui."""

from .main import main  # noqa: F401
