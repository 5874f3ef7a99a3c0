"""Write the built-in maps (``src/firefleet/world/maps/<name>.yaml`` and ``.pgm``).

The plans are drawn by :mod:`firefleet.world._plans`; this script only writes them, so
the shipped files are reproducible: ``python tools/make_maps.py`` then ``git diff``
shows nothing. ``tests/world/test_maps.py`` checks the shipped files equal the plans.
"""

from __future__ import annotations

from pathlib import Path

from firefleet.world._plans import PLANS, encode_pgm, map_yaml


def main() -> None:
    folder = Path(__file__).resolve().parents[1] / "src" / "firefleet" / "world" / "maps"
    folder.mkdir(exist_ok=True)
    for name, draw in PLANS.items():
        (folder / f"{name}.pgm").write_bytes(encode_pgm(draw()))
        (folder / f"{name}.yaml").write_text(map_yaml(f"{name}.pgm"), encoding="utf-8")


if __name__ == "__main__":
    main()
