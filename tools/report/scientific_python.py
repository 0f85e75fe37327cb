"""The scientific Python modules a tool needs, or a re-run under Debian's python3.

Debian's /usr/bin/python3 has numpy, matplotlib and scikit-learn (the
project's setup installs them); a pyenv or virtualenv python3 that comes first
on PATH may not. ensure() re-runs the script under /usr/bin/python3 rather
than let it fail with an ImportError deep inside a module.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Sequence

DEBIAN_PYTHON = "/usr/bin/python3"
EXIT_ERROR = 1


def ensure(modules: Sequence[str], debian_packages: str) -> None:
    """Returns if every module imports; else re-runs the script under Debian's
    python3 (once), or exits naming the missing module and the packages."""
    missing = None
    for name in modules:
        try:
            importlib.import_module(name)
        except ImportError:
            missing = name
            break
    if missing is None:
        return
    if (os.path.exists(DEBIAN_PYTHON) and os.path.realpath(sys.executable) != os.path.realpath(DEBIAN_PYTHON)
            and not os.environ.get("IVOA_REPORT_REEXEC")):
        os.environ["IVOA_REPORT_REEXEC"] = "1"
        print(f"note: {sys.executable} has no module '{missing}'; re-running with {DEBIAN_PYTHON}", file=sys.stderr)
        sys.stderr.flush()
        os.execv(DEBIAN_PYTHON, [DEBIAN_PYTHON, os.path.abspath(sys.argv[0])] + sys.argv[1:])
    print(f"error: Python module '{missing}' is missing; install Debian's {debian_packages} "
          "(tools/setup/debian-packages.txt)", file=sys.stderr)
    sys.exit(EXIT_ERROR)
