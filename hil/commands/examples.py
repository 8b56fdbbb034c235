"""`hil examples DIR`: copy the shipped example benches and programs out of the installed package,
so the guide's commands (`hil run examples/lathe_demo.nc --bench benches/lathe-2axis.toml`) work
from DIR after a plain `pip install deltahil`."""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path

EXIT_OK, EXIT_USAGE = 0, 2


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("examples", help="copy the example benches/ and examples/ into a folder")
    p.add_argument("dir", help="target folder (created if missing); it gets benches/ and examples/")
    p.add_argument("--force", action="store_true", help="overwrite files that are already there")
    p.set_defaults(func=cmd_examples)


def cmd_examples(args: argparse.Namespace) -> int:
    from hil.shipped import BENCHES, EXAMPLES

    target = Path(args.dir)
    if target.exists() and not target.is_dir():
        print(f"hil examples: {target} is not a folder", file=sys.stderr)
        return EXIT_USAGE
    pairs = [(src, target / top / src.relative_to(root)) for top, root in (("benches", BENCHES),
                                                                             ("examples", EXAMPLES))
             for src in sorted(root.rglob("*")) if src.is_file() and "__pycache__" not in src.parts]
    clash = [dst for _, dst in pairs if dst.exists()]
    if clash and not args.force:
        print(f"hil examples: {len(clash)} file(s) already there, e.g. {clash[0]}; --force overwrites them",
              file=sys.stderr)
        return EXIT_USAGE
    try:
        for src, dst in pairs:
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, dst)
    except OSError as exc:
        print(f"hil examples: {exc.filename}: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE
    print(f"copied {len(pairs)} files to {target}/benches and {target}/examples")
    print(f"try: cd {target} && hil run examples/lathe_demo.nc --bench benches/lathe-2axis.toml")
    return EXIT_OK
