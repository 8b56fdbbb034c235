"""Program store: O-numbered subprograms and macros, found the way NC5 searches its folders.

NC5 ch.2 / N§3.11 (seed-catalog §2.10): a library root is a "(DISK)" with ``PATH_1``,
``PATH_1/O_MACRO``, ``GLOBAL`` and ``GLOBAL/O_MACRO``.  With ``N8.22 Bit5 = 0``:

* M98 / M96 / G65 / G66 search (1) the folder of the main program, (2) (DISK)/PATH_□,
  (3) (DISK)/PATH_□/O_MACRO, (4) (DISK)/GLOBAL, (5) (DISK)/GLOBAL/O_MACRO;
* G-, M- and T-code macros (and the initial macro) search (2)…(5) first and the main program's
  folder last.

(``N8.22 Bit5 = 1`` puts a USB root first; a bench gives it as ``usb``.)  A file is named
``O0001``, ``O0001.NC`` (any case) or ``O1`` …; a file may also hold several O programs, and every
O program of the main file and of files given with ``--lib FILE`` is registered first (decisions A23).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from nc.alarms import NcAlarm
from nc.program.blocks import MAX_DIGITS, Program, parse_programs

SUFFIXES = ("", ".NC", ".nc", ".txt", ".TXT", ".ngc")


@dataclass
class ProgramStore:
    roots: list[Path] = field(default_factory=list)  # (DISK) roots, searched in order
    main_dir: Path | None = None
    usb: Path | None = None
    path_index: int = 1  # NC path number (PATH_1)
    usb_first: bool = False  # N8.22 Bit5
    loaded: dict[int, Program] = field(default_factory=dict)

    def add_text(self, text: str, name: str = "program") -> list[Program]:
        """Register every O program of a text; returns them (the first is the main program)."""
        progs = parse_programs(text, name)
        for p in progs:
            if p.number is not None:
                self.loaded.setdefault(p.number, p)
        return progs

    def add_file(self, path: Path, named: bool = False) -> list[Program]:
        """Register a subprogram file found by `find`; an alarm in it names the file and its line
        (the interpreter adds the calling block). `named`: a file the user gave (--lib FILE) is
        parsed as given, binary or not."""
        text = read_program(path, 0x0263, refuse_binary=not named)
        try:
            return self.add_text(text, path.name)
        except NcAlarm as exc:
            exc.alarm = replace(exc.alarm, program=str(path))
            exc.caller_missing = True
            raise

    def add_libs(self, libs: list[str] | tuple[str, ...]) -> None:
        """``--lib DIR|FILE``: a file's O programs are registered now, a folder is a (DISK) root
        searched in the NC5 order.  Raises ValueError naming a path that is neither."""
        for lib in libs:
            lp = Path(lib)
            if lp.is_file():
                self.add_file(lp, named=True)
            elif lp.is_dir():
                self.roots.append(lp)
            else:
                raise ValueError(f"--lib {lib}: no such file or folder")

    def load_main(self, path: str) -> Program:
        """The main program of a file; every further O program of the file is registered (A23).
        The program keeps this store, so any interpreter that runs it finds its subprograms."""
        p = Path(path)
        text = read_program(p, 0x0002, refuse_binary=False)  # the file the user named: parsed as given
        self.main_dir = p.parent
        try:
            progs = self.add_text(text, p.name)
        except NcAlarm as exc:
            raise exc.at(None, None, p.name)
        main = progs[0]
        main.name = p.name
        main.store = self
        return main

    def folders(self, macro_call: bool) -> list[Path]:
        disk: list[Path] = []
        for r in self.roots:
            disk += [r / f"PATH_{self.path_index}", r / f"PATH_{self.path_index}" / "O_MACRO",
                     r / "GLOBAL", r / "GLOBAL" / "O_MACRO", r]
        main = [self.main_dir] if self.main_dir is not None else []
        order = disk + main if macro_call else main + disk
        if self.usb_first and self.usb is not None:
            order = [self.usb] + order
        return order

    def program_roots(self) -> list[Path]:
        """Folders a subprogram file may resolve into (symlinks included): the main program's
        folder, the --lib / bench (DISK) roots and the USB root (decisions P4)."""
        roots = [r for r in (self.main_dir, self.usb, *self.roots) if r is not None]
        return [r.resolve() for r in roots]

    def _inside_roots(self, cand: Path) -> bool:
        real = cand.resolve()
        return any(real.is_relative_to(r) for r in self.program_roots())

    def find(self, number: int, macro_call: bool = False, code: int = 0x0263) -> Program:
        """The program O<number>; raises NcAlarm(code) if no folder holds it, or if the file found
        resolves (through a symlink) outside every program root."""
        if number in self.loaded:
            return self.loaded[number]
        if not 0 <= number < 10 ** MAX_DIGITS:
            shown = str(number) if len(str(number)) <= 12 else f"{str(number)[:12]}… ({len(str(number))} digits)"
            raise NcAlarm(code, f"P{shown} is not a program number (O0001-O9999; at most {MAX_DIGITS} digits)")
        names = {f"O{number:04d}", f"O{number}", f"O{number:05d}"}
        for folder in self.folders(macro_call):
            if not folder.is_dir():
                continue
            for base in names:
                for suf in SUFFIXES:
                    for cand in (folder / (base + suf), folder / (base.lower() + suf)):
                        if cand.is_file():
                            if not self._inside_roots(cand):
                                raise NcAlarm(code, f"{cand} resolves outside the program folders: refused")
                            progs = self.add_file(cand)
                            hit = next((p for p in progs if p.number == number), progs[0])
                            hit.number = number
                            hit.path = str(cand)
                            self.loaded[number] = hit
                            return hit
        raise NcAlarm(code, f"program O{number:04d} not found"
                      + (f" (searched {', '.join(str(f) for f in self.folders(macro_call) if f.is_dir())})"
                         if self.roots or self.main_dir else ""))


BINARY_SNIFF = 8192  # bytes looked at to tell a text program from a binary file


def read_program(path: Path, code: int, refuse_binary: bool = True) -> str:
    """The text of a program file, or NcAlarm(code) naming the file -- never its contents when it
    is not a program (a binary file found by the subprogram search, or one that cannot be read)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise NcAlarm(code, f"program file {path} cannot be read: {exc.strerror or exc}",
                      program=path.name) from None
    if refuse_binary and b"\0" in data[:BINARY_SNIFF]:
        raise NcAlarm(code, f"{path} is not a program (binary data)", program=path.name)
    return data.decode("utf-8", errors="replace")
