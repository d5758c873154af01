#!/usr/bin/env python3
"""Summarises a `lanechange crosscheck --out FILE` run as a Markdown section."""
import json
import statistics
import sys
from collections import Counter


def quantiles(values, qs=(0.5, 0.9, 0.99, 1.0)):
    values = sorted(values)
    if not values:
        return ["-"] * len(qs)
    return [values[min(len(values) - 1, int(q * (len(values) - 1) + 0.5))] for q in qs]


def main(path):
    rows = [json.loads(line) for line in open(path) if line.strip()]
    agree = sum(r["agree"] for r in rows)
    verdicts = Counter((r["fast_status"], r["reference_status"]) for r in rows)
    solved = [r for r in rows if r["fast_status"] == "Optimal" and r["reference_status"] == "Optimal"]
    print(f"- cases: {len(rows)}; agree (same verdict, objectives within 1e-6 relative): **{agree}**")
    for (fast, ref), n in sorted(verdicts.items()):
        print(f"- fast {fast} / reference {ref}: {n}")
    if solved:
        q = quantiles([r["relative_difference"] for r in solved])
        print("- relative objective difference on the solved cases, median / 90% / 99% / max: "
              + " / ".join(f"{v:.1e}" for v in q))
    fast = [r["fast_ms"] for r in rows]
    ref = [r["reference_ms"] for r in rows]
    # A replayed file holds the fast side of the replay and the reference of the
    # original run: the two times then come from different runs and code.
    print(f"- median wall time per MIQP: fast {statistics.median(fast):.2f} ms, "
          f"reference {statistics.median(ref):.0f} ms (a replayed file mixes runs; "
          "docs/performance.md has a same-run ratio)")
    print(f"- median QPs (fast) {statistics.median(r['fast_nodes'] for r in rows):.0f}, "
          f"median Bonmin nodes {statistics.median(r['reference_nodes'] for r in rows):.0f}")
    undecided = ("TimeLimit", "NodeLimit")
    for r in rows:
        if r["agree"]:
            continue
        kind = ("undecided (a solver hit its limit)"
                if r["fast_status"] in undecided or r["reference_status"] in undecided
                else "DISAGREEMENT")
        print(f"- {kind}: index {r['index']} ({r['behavior']}): fast {r['fast_status']} "
              f"{r['fast_objective']}, reference {r['reference_status']} {r['reference_objective']} "
              f"after {r['reference_ms'] / 1000:.0f} s")


if __name__ == "__main__":
    main(sys.argv[1])
