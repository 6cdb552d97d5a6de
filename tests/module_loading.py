"""Which modules a fresh interpreter has loaded after running some code (import-cost tests)."""

import json
import subprocess
import sys


def loaded(code: str, *argv: object) -> set[str]:
    """The modules loaded after running ``code`` (which may run the CLI with ``argv``)."""
    script = (
        "import json, sys\n"
        f"sys.argv = ['anklelab', *{list(map(str, argv))!r}]\n"
        "try:\n"
        f"    {code}\n"
        "except SystemExit:\n"
        "    pass\n"
        "sys.stderr.write('\\nMODULES ' + json.dumps(sorted(sys.modules)))\n"
    )
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert "MODULES " in proc.stderr, proc.stderr
    return set(json.loads(proc.stderr.rsplit("MODULES ", 1)[1]))
