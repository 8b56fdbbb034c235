"""The example benches (benches/) and programs, MLC modules and scripts (examples/) shipped with
deltahil; at the top of the repository `benches` and `examples` are links to these folders."""

from pathlib import Path

SHIPPED = Path(__file__).parent
BENCHES = SHIPPED / "benches"
EXAMPLES = SHIPPED / "examples"
