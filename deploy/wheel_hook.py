"""Hatch build hook: the installed wheel's ``livedrummer`` command enters the process layer.

The repository keeps the pure library (``livedrummer/``) and the processes with their CLI
(``services/``) side by side. A wheel must put nothing but ``livedrummer`` into
site-packages, so ``pyproject.toml`` copies ``services/`` into the wheel as
``livedrummer/_services`` (every module there imports its siblings relatively, so the code
runs unchanged under that name; see ``services/process/program.py``). In a checkout and an editable
install the command's entry point is ``services.cli:main``; this hook rewrites it, for the
standard wheel only, to the name the same code has inside the wheel. Editable installs keep
the checkout's name (hatch cannot remap a package's prefix in editable mode).
"""

from __future__ import annotations

from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

#: Where ``pyproject.toml``'s force-include puts ``services/`` inside the wheel.
INSIDE_WHEEL = "livedrummer._services"


class WheelEntryPoint(BuildHookInterface):  # type: ignore[misc]
    PLUGIN_NAME = "custom"

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        if version != "standard":
            return
        scripts = self.metadata.core.scripts
        for name, target in scripts.items():
            if target.startswith("services."):
                scripts[name] = INSIDE_WHEEL + target[len("services") :]
