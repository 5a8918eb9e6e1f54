"""Finds the gyroid offset that gives a block 30 % solid, by bisection, building with
`latticebuild build --set ... --report -` and reading the JSON report.

    python3 examples/optimizer_loop.py [LATTICEBUILD] [MANIFEST]

The manifest's `formats = []` writes no mesh (the report is measured all the same), and the
cache keeps every offset tried, so asking again for one is a cache hit.
"""
import json
import subprocess
import sys

latticebuild = sys.argv[1] if len(sys.argv) > 1 else "latticebuild"
manifest = sys.argv[2] if len(sys.argv) > 2 else "examples/optimizer_loop.toml"


def build(offset):
    """The report of output `block` built with `offset`."""
    run = subprocess.run(
        [latticebuild, "build", manifest, "-q", "--report", "-",
         "--set", f"outputs.block.offset={offset!r}"],
        capture_output=True, text=True)
    [report] = json.loads(run.stdout)  # one output; a failed one has "status": "failed"
    if run.returncode != 0 or report["status"] != "built":
        sys.exit(f"build failed: {report.get('error', run.stderr)}")
    return report


target, low, high = 0.30, -1.5, 1.5  # the solid (f <= offset) grows with the offset
for step in range(12):
    offset = (low + high) / 2
    fraction = build(offset)["volume_fraction"]
    print(f"step {step:2}: offset {offset:+.5f} -> volume fraction {fraction:.4f}")
    if fraction < target:
        low = offset
    else:
        high = offset
best = build((low + high) / 2)
print(f"offset {best['parameters']['offset']:+.5f}: volume fraction "
      f"{best['volume_fraction']:.4f}, {best['components']} piece(s) "
      f"(report schema {best['schema_version']}, latticebuild {best['tool_version']})")
again = build(offset)  # an offset tried before: every stage comes from the cache
cached = sum(stage["cached"] for stage in again["stages"])
print(f"offset {offset:+.5f} again: {cached} of {len(again['stages'])} stages cached")
