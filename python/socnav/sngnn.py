"""The SNGNN-v2 weights from Python: where socnav looks for them, and installing them.

The weights (``SOCNAV_V2.tch``) are GPL-3.0 and not part of socnav. ``install_weights()`` does
what ``socnav sngnn install`` does on the command line: it downloads the socnavgym 0.1.1 wheel
with this interpreter's pip (no dependencies), copies the one file into socnav's cache and checks
it. Configs with ``reward.kind = "sngnn"`` (``"exp1_sngnn"``, ``"exp2_sngnn"``, ``"exp3_sngnn"``)
then load it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

from socnav._socnav import SngnnError, sngnn_install_from_wheel, sngnn_paths

__all__ = ["install_weights", "weights_path"]

_WHEEL = "socnavgym==0.1.1"


def weights_path() -> Path:
    """The weight file socnav loads: ``SOCNAV_SNGNN_WEIGHTS`` when set, else the cache file
    (``$SOCNAV_CACHE_DIR``, ``$XDG_CACHE_HOME/socnav`` or ``~/.cache/socnav``, then
    ``sngnn/SOCNAV_V2.tch``). A config's ``reward.sngnn_weights`` overrides the cache."""
    return Path(sngnn_paths()[0])


def install_weights(*, force: bool = False, quiet: bool = False) -> Path:
    """Download the socnavgym 0.1.1 wheel with pip and install its SNGNN-v2 weights into the
    cache; returns the installed file. A valid installed file is kept unless ``force``.

    Raises:
        SngnnError: pip failed (no network, no pip) or the wheel holds no valid weight file.
    """
    dest = Path(sngnn_paths()[1])
    if dest.is_file() and not force:
        return dest
    with tempfile.TemporaryDirectory(prefix="socnav-sngnn-") as tmp:
        wheel = _download_wheel(Path(tmp), quiet)
        parameters = sngnn_install_from_wheel(str(wheel), str(dest))
    if not quiet:
        print(
            f"socnav: installed the SNGNN-v2 weights ({parameters} parameters) at {dest}; "
            "the file is GPL-3.0 (from the socnavgym 0.1.1 wheel) and socnav does not "
            "redistribute it",
            file=sys.stderr,
        )
    override = os.environ.get("SOCNAV_SNGNN_WEIGHTS")
    if override and Path(override) != dest:
        print(f"socnav: note: SOCNAV_SNGNN_WEIGHTS={override} takes precedence", file=sys.stderr)
    return dest


def _download_wheel(into: Path, quiet: bool) -> Path:
    """The socnavgym 0.1.1 wheel, downloaded into ``into`` with this interpreter's pip."""
    command = [sys.executable, "-m", "pip", "download", _WHEEL, "--no-deps",
               "--only-binary=:all:", "-d", str(into)]
    if not quiet:
        print(f"socnav: downloading the {_WHEEL} wheel (about 16 MB) with pip", file=sys.stderr)
    done = subprocess.run(command, capture_output=True, text=True)
    wheels = sorted(into.glob("socnavgym-0.1.1-*.whl"))
    if done.returncode != 0 or not wheels:
        tail = "\n".join((done.stderr or done.stdout).strip().splitlines()[-5:])
        raise SngnnError(
            f"could not download the {_WHEEL} wheel with `{' '.join(command[:4])} ...` "
            f"(exit status {done.returncode}):\n{tail}"
        )
    return wheels[0]
