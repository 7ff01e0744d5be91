#!/usr/bin/env python3
"""Turns docs/accuracy/budget.csv (tools/accuracy/budget.sh) into the table of
docs/accuracy/budget.md: for each scene and CPU budget, the planner's render against the
defaults with their samples raised to the same CPU time and against the best grid setting that
took no more CPU time than the planner's render."""
import csv
import sys


def main(path):
    rows = list(csv.DictReader(open(path)))
    scenes = []
    for r in rows:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    print("| scene | budget (CPU s) | planner: spp, CPU s, rel. RMSE | expected (ratio) "
          "| defaults, more spp: spp, CPU s, rel. RMSE | planner / defaults "
          "| best grid setting in the planner's CPU time | planner / grid "
          "| against caustic's long renders (expected / it) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scene in scenes:
        mine = [r for r in rows if r["scene"] == scene]
        grid = [r for r in mine if r["kind"] == "grid"]
        for b in [r for r in mine if r["kind"] == "budget"]:
            cpu, err = float(b["cpu"]), float(b["rel_rmse"])
            exp = float(b["expected"])
            d = [r for r in mine if r["kind"] == "defaults" and r["budget_cpu"] == b["budget_cpu"]]
            dtext, dratio = "", ""
            if d:
                d = d[0]
                dtext = f"{d['spp']}, {float(d['cpu']):.1f}, {float(d['rel_rmse']):.4f}"
                dratio = f"{err / float(d['rel_rmse']):.2f}"
            fit = [g for g in grid if float(g["cpu"]) <= cpu]
            gtext, gratio = "none as fast", ""
            if fit:
                g = min(fit, key=lambda g: float(g["rel_rmse"]))
                gtext = f"{g['setting']}: {float(g['cpu']):.1f} s, {float(g['rel_rmse']):.4f}"
                gratio = f"{err / float(g['rel_rmse']):.2f}"
            own = [r for r in mine if r["kind"] == "self" and r["budget_cpu"] == b["budget_cpu"]]
            otext = ""
            if own:
                o = float(own[0]["rel_rmse"])
                otext = f"{o:.4f} ({exp / o:.2f})"
            print(f"| {scene} | {b['budget_cpu']} | {b['spp']} ({b['setting']}), {cpu:.1f}, {err:.4f} "
                  f"| {exp:.4f} ({exp / err:.2f}) | {dtext} | {dratio} | {gtext} | {gratio} "
                  f"| {otext} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/accuracy/budget.csv")
