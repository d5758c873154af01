#!/usr/bin/env python3
"""Summarises a comparison with the authors' records (docs/authors_comparison.md).

    scripts/authors_summary.py RUN_DIR [RECORDS_JSONL] [--baseline OTHER_RUN_DIR]

RUN_DIR holds comparisons.jsonl, as written by
`lanechange authors-study`. With the records file, the shares are
also given per distinct scenario (the 1283 records hold 669 distinct
scenarios: many cells of data2..data8.mat repeat one another). With a
baseline run, the records whose verdict changed are listed.
"""
import argparse
import collections
import json
import math
import os


def load(run_dir):
    with open(os.path.join(run_dir, "comparisons.jsonl")) as f:
        return [json.loads(line) for line in f if line.strip()]


def quantile(values, q):
    v = sorted(x for x in values if x is not None and math.isfinite(x))
    if not v:
        return float("nan")
    pos = q * (len(v) - 1)
    lo = math.floor(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (pos - lo) * (v[hi] - v[lo])


def ok_within(c, tol):
    r = c["relative_difference"]
    return r is not None and r <= tol


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir")
    ap.add_argument("records", nargs="?")
    ap.add_argument("--baseline")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--list", type=int, default=15, help="records listed per cause")
    a = ap.parse_args()
    comps = load(a.run_dir)
    tol = a.tolerance
    solved = [c for c in comps if c["theirs_solved"]]
    none = [c for c in comps if not c["theirs_solved"]]
    n_ok = sum(ok_within(c, tol) for c in solved)
    n_agree_none = sum(c["our_status"] != "converged" for c in none)
    print(f"records {len(comps)}: their solved {len(solved)}, no_solution {len(none)}")
    print(f"at most {100*tol:g}% above theirs: {n_ok}/{len(solved)} = {100*n_ok/len(solved):.1f}%")
    for t in (0.001, 0.005, 0.01, 0.02, 0.05, 0.10):
        k = sum(ok_within(c, t) for c in solved)
        w = sum(c["relative_difference"] is not None and abs(c["relative_difference"]) <= t
                for c in solved)
        print(f"  tol {100*t:4.1f}%: at most above {k} ({100*k/len(solved):.1f}%), "
              f"within +- {w} ({100*w/len(solved):.1f}%)")
    print(f"no_solution agreed (we fail too): {n_agree_none}/{len(none)}")
    print("our status on their no_solution records:",
          dict(collections.Counter(c["our_status"] for c in none)))
    print("our status on their solved records:",
          dict(collections.Counter(c["our_status"] for c in solved)))
    print("agreement:", dict(collections.Counter(c["agreement"] for c in comps)))
    print("cause:", dict(collections.Counter(c["cause"] for c in comps)))

    if a.records:
        with open(a.records) as f:
            recs = [json.loads(line) for line in f if line.strip()]
        key = {r["id"]: json.dumps(r["scenario"], sort_keys=True) for r in recs}
        first = {}
        for c in comps:
            first.setdefault(key[c["id"]], c)
        uniq = list(first.values())
        us = [c for c in uniq if c["theirs_solved"]]
        un = [c for c in uniq if not c["theirs_solved"]]
        k = sum(ok_within(c, tol) for c in us)
        kn = sum(c["our_status"] != "converged" for c in un)
        print(f"distinct scenarios {len(uniq)}: solved {len(us)}, at most {100*tol:g}% above "
              f"{k} ({100*k/max(1,len(us)):.1f}%); no_solution {len(un)}, agreed {kn}")

    qs = (0.0, 0.01, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95, 0.99, 1.0)
    both = [c for c in solved if c["relative_difference"] is not None]
    rows = {
        "rel. difference": [c["relative_difference"] for c in both],
        "max |dx| m": [c["max_dx"] for c in both],
        "max |dy| m": [c["max_dy"] for c in both],
        "max |dv| m/s": [c["max_dv"] for c in both],
        "their gap": [c["their_gap"] for c in both],
        "prediction effect": [c["prediction_effect"] for c in both],
        "fixpoint effect": [c["fixpoint_effect"] for c in both],
        "their lanes viol., their pred.": [
            c["with_their_prediction"]["violation"]["lanes"] for c in solved],
        "their lanes viol., our pred.": [
            c["with_our_prediction"]["violation"]["lanes"] for c in solved],
        "their dyn. viol. at their point": [
            c["with_their_prediction"]["violation"]["dynamics"] for c in solved],
        "pred. leader dx": [c["prediction_max_dx"]["leader"] for c in solved],
        "pred. follower dx": [c["prediction_max_dx"]["follower"] for c in solved],
        "pred. target dx": [c["prediction_max_dx"]["target"] for c in solved],
        "iterations (ours)": [c["iterations"] for c in comps],
        "plan ms": [c["ms"] for c in comps],
    }
    print("\n| quantity | " + " | ".join(f"p{100*q:g}" for q in qs) + " |")
    print("|---|" + "---:|" * len(qs))
    for name, vals in rows.items():
        print(f"| {name} | " + " | ".join(f"{quantile(vals, q):.4g}" for q in qs) + " |")

    print("\nDisagreements by cause (worst first):")
    by_cause = collections.defaultdict(list)
    for c in comps:
        if c["cause"] != "none":
            by_cause[c["cause"]].append(c)
    for cause, cs in sorted(by_cause.items()):
        cs.sort(key=lambda c: -abs(c["relative_difference"] or 0))
        print(f"\n{cause} ({len(cs)}):")
        for c in cs[: a.list]:
            v = c["with_our_prediction"]["violation"]
            vq = c["their_violation_in_our_qp"]
            def f(x):
                return "-" if x is None else f"{x:.4g}"
            print(f"  {c['id']:16s} ours {c['our_status']:15s} it {c['iterations']:2d} "
                  f"obj {f(c['our_objective'])} theirs {f(c['their_objective'])} "
                  f"rel {f(c['relative_difference'])} = gap {f(c['their_gap'])} + pred {f(c['prediction_effect'])} + fix {f(c['fixpoint_effect'])} "
                  f"their lanes viol. (our pred.) {f(v['lanes'])} "
                  f"their_in_ourqp {f(c['their_objective_in_our_qp'])} "
                  f"(lanes {f(vq['lanes'])} dyn {f(vq['dynamics'])}) "
                  f"cross {c['our_first_cross_node']}/{c['their_first_cross_node']} "
                  f"dx {f(c['max_dx'])} dy {f(c['max_dy'])}")

    if a.baseline:
        base = {c["id"]: c for c in load(a.baseline)}
        changed = collections.Counter()
        for c in comps:
            b = base.get(c["id"])
            if b is None:
                continue
            was, now = ok_within(b, tol) if b["theirs_solved"] else b["our_status"] != "converged", \
                ok_within(c, tol) if c["theirs_solved"] else c["our_status"] != "converged"
            if was != now:
                changed["fixed" if now else "broken"] += 1
        print("\nagainst the baseline:", dict(changed))


if __name__ == "__main__":
    main()
