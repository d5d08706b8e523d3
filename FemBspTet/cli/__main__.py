# SPDX-License-Identifier: LGPL-2.1-or-later
"""``python3 -m FemBspTet.cli ARGS``: the ``fembsptet`` command."""

import sys

from .main import main

sys.exit(main())
