"""docs/results.md: the headline figures of every run under out/, beside the paper's tables.

Usage: results.py [OUT_DIR=out] [--img docs/img] [--md docs/results.md]

Reads OUT_DIR/*/summary.json (folders without one are skipped with a message; out/mesh,
out/test and out/bench are not runs of the examples), the archive's tool version, the
pictures that pipelines/report.py made in --img (linked by file name <run>_*.png), and the
vault tables of pipelines/vault_table.py (OUT_DIR/vault/table3.md, table4.md) when present.
"""
import argparse
import datetime
import json
import os
import pathlib
import sys

SKIP = {"mesh", "test", "bench", "accuracy", "vault"}  # vault: the tables of vault_table.py

# The paper's Tables 1 and 2: detached length (cm) and CPU time (s) per method.
PAPER_TABLES = [
    {
        "title": "Example 1 — beam on elastic blocks (the paper's Table 1)",
        "runs": ["beam_on_blocks", "beam_on_blocks_slide"],
        "interface": "support",
        "rows": [("SGBEM iterative LCP", "lcp", 8.4, 237.7),
                 ("BEM (Vodička)", None, 8.3, None),
                 ("SGBEM QPP", "qp", 8.2, 4.3)],
        "note": ("The paper's model is \"no friction and no sliding\": `beam_on_blocks` reads it as stick "
                 "(closed pairs bonded in both directions), `beam_on_blocks_slide` as frictionless "
                 "sliding. The paper's CPU times are for its Karnak.sGbem + MATLAB 7.6 implementation "
                 "(2010 hardware); sgbem's are wall-clock seconds of the contact stage alone and of the "
                 "whole run (read, assembly, condensation, contact, post-processing, writing)."),
    },
    {
        "title": "Example 2 — clamped beam with a mid-span joint (the paper's Table 2)",
        "runs": ["clamped_beam_joint"],
        "interface": "joint",
        "rows": [("SGBEM iterative LCP", "lcp", 33.85, 984.4),
                 ("SGBEM QPP", "qp", 33.08, 16.2)],
        "note": ("The paper's CPU times are for its Karnak.sGbem + MATLAB 7.6 implementation; "
                 "sgbem's are wall-clock seconds of the contact stage alone and of the whole run."),
    },
]

STAGES = ["read", "assemble", "condense", "interface_system", "solve", "contact_lcp", "contact_record",
          "contact_active_set", "contact_lemke", "contact_qp", "postprocess", "write", "total"]


def num(v, digits=4):
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    try:
        v = float(v) + 0.0
    except (TypeError, ValueError):
        return str(v)
    if v == 0:
        return "0"
    if 1e-3 <= abs(v) < 1e5:
        return f"{v:.{digits}g}"
    return f"{v:.3e}"


def secs(v):
    if v is None:
        return "—"
    v = float(v)
    return f"{v:.3g}" if v >= 1e-3 else f"{v:.1e}"


def table(head, rows):
    out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def tool_version(run):
    try:
        import h5py
        with h5py.File(run / "archive.h5", "r") as h5:
            v = h5.attrs.get("tool_version", "")
            return v.decode() if isinstance(v, bytes) else str(v)
    except Exception:
        return ""


def load_runs(out_dir):
    runs = {}
    if not out_dir.is_dir():
        print(f"results: {out_dir} does not exist: run `make examples` first")
        return runs
    for d in sorted(p for p in out_dir.iterdir() if p.is_dir() and p.name not in SKIP):
        f = d / "summary.json"
        if not f.exists():
            print(f"results: {d}: no summary.json: skipped")
            continue
        try:
            summary = json.loads(f.read_text())
            # Timings live in timings.json (summary.json is the same for identical runs).
            t = d / "timings.json"
            if t.exists():
                summary["timings"] = json.loads(t.read_text()).get("stages", {})
            runs[d.name] = (d, summary)
        except Exception as e:
            print(f"results: {f}: unreadable ({e}): skipped")
    return runs


def pictures(img_dir, md_dir, name):
    if not img_dir.is_dir():
        return []
    # names are <run>_<what>.png; a run's name may be the prefix of another's (beam_on_blocks)
    out = []
    for p in sorted(img_dir.glob(f"{name}_*.png")):
        rest = p.stem[len(name) + 1:]
        if any(p.stem.startswith(o + "_") and len(o) > len(name) for o in pictures.names):
            continue
        out.append((rest, os.path.relpath(p, md_dir)))
    order = ["shape", "detachment", "sections", "sections_history", "beam"]
    return sorted(out, key=lambda r: next((k for k, w in enumerate(order) if r[0] == w or r[0].endswith("_" + w)),
                                          len(order)))


pictures.names = []

CAPTIONS = [
    ("shape", "strained shape of the final state, coloured by σxx and von Mises (magnification in the title)"),
    ("detachment", "normal opening and status along each interface per contact iteration; detached length per iteration"),
    ("sections_history", "normal stress on each section for states of the contact iterations "
                         "(for example 2 the paper's Fig. 6)"),
    ("sections", "normal and shear stresses along each section, final state"),
    ("beam", "σx and τxy at the section against beam theory for the continuous clamped beam (the paper's Fig. 5)"),
]


def caption(rest):
    for key, text in CAPTIONS:
        if rest == key or rest.endswith("_" + key):
            return text
    return rest


def paper_table(spec, runs):
    lines = [f"### {spec['title']}", ""]
    present = [r for r in spec["runs"] if r in runs]
    if not present:
        lines += [f"_No run folder for {', '.join(spec['runs'])} under out/: run `make examples`._", ""]
        return lines
    head = ["method", "paper: detached (cm)"] + [f"`{r}`: detached (cm)" for r in present] + \
           ["paper: CPU (s)"] + [f"`{r}`: contact / total (s)" for r in present]
    rows = []
    iface = spec["interface"]
    for label, key, d_paper, t_paper in spec["rows"]:
        det, tim = [], []
        for r in present:
            s = runs[r][1]
            t = s.get("timings", {})
            if key == "lcp":
                fig = s.get("interfaces", {}).get(iface, {})
                det.append(num(fig.get("detached_length")))
                tim.append(f"{secs(t.get('contact_lcp'))} / {secs(t.get('total'))}")
            elif key == "qp" and "qp" in s:
                fig = s["qp"].get("interfaces", {}).get(iface, {})
                det.append(num(fig.get("detached_length")))
                tim.append(f"{secs(t.get('contact_qp'))} / {secs(t.get('total'))}")
            else:
                det.append("—")
                tim.append("—")
        rows.append([label, num(d_paper)] + det + [num(t_paper) if t_paper else "—"] + tim)
    lines += [table(head, rows), "", spec["note"], ""]
    for r in present:
        s = runs[r][1]
        c = s.get("contact", {})
        extra = []
        if c:
            extra.append(f"LCP {c.get('iterations', '—')} iterations, converged {num(c.get('converged'))}, "
                         f"complementarity residual {num(c.get('complementarity_residual'))}")
        if "qp" in s:
            q = s["qp"]
            info = q.get("info", {})
            own = q.get("interfaces", {}).get(iface, {})
            extra.append(f"QP {info.get('iterations', '—')} interior-point iterations "
                         f"({info.get('solver_status', '—')}), its own zones (no polishing) "
                         f"{num(own.get('detached_length'))} cm detached")
        checks = c.get("cross_checks", [])
        if checks:
            extra.append("pairs differing from the LCP: " + ", ".join(
                f"{x.get('solver', '?')} {x.get('differing_pairs', '—')}" for x in checks))
        for n in s.get("notes", []):
            extra.append(f"note: {n}")
        if extra:
            lines.append(f"- `{r}`: " + "; ".join(extra))
    lines.append("")
    return lines


def run_section(name, path, s, img_dir, md_dir):
    lines = [f"### `{name}` — {s.get('title', name)}", ""]
    units = s.get("units", {})
    L, F = units.get("length", ""), units.get("force", "")
    c = s.get("counts", {})
    contact = s.get("contact", {})
    head = [
        ("status", s.get("status", "—")),
        ("method", s.get("method", "—")),
        ("problem / effects", f"{s.get('problem', '—')} / {', '.join(s.get('effects', []))}"),
        ("plane, thickness", f"{s.get('plane', '—')}, {num(s.get('thickness'))} {L}"),
        ("bodies, boundary elements, interface pairs, dofs",
         f"{c.get('bodies', '—')}, {c.get('boundary_elements', '—')}, {c.get('interface_pairs', '—')}, {c.get('dofs', '—')}"),
        ("contact solver", contact.get("solver", "—")),
    ]
    if "iterations" in contact:
        head.append(("LCP iterations, load steps", f"{contact['iterations']}, {contact.get('load_steps', '—')}"))
        head.append(("complementarity residual", num(contact.get("complementarity_residual"))))
    if "qp" in s:
        head.append(("QP iterations", s["qp"].get("info", {}).get("iterations", "—")))
    v = tool_version(path)
    if v:
        head.append(("sgbem version", v))
    lines += [table(["", ""], head), ""]

    ifaces = s.get("interfaces", {})
    if ifaces:
        keys = [("detached_length", f"detached ({L})"), ("closed_length", f"closed ({L})"),
                ("open_pairs", "open pairs"), ("pairs", "pairs"),
                ("normal_resultant", f"normal resultant ({F})"),
                ("tangential_resultant", f"tangential resultant ({F})"),
                ("min_normal_traction", f"min tn ({F}/{L}²)"), ("max_normal_traction", f"max tn ({F}/{L}²)")]
        rows = []
        for iname, fig in ifaces.items():
            rows.append([f"{iname} (LCP)"] + [num(fig.get(k)) for k, _ in keys])
            q = s.get("qp", {}).get("interfaces", {}).get(iname)
            if q:
                rows.append([f"{iname} (QP)"] + [num(q.get(k)) for k, _ in keys])
        lines += [table(["interface"] + [h for _, h in keys], rows), ""]

    t = s.get("timings", {})
    if t:
        stages = [k for k in STAGES if k in t] + [k for k in t if k not in STAGES]
        lines += [table([f"{k} (s)" for k in stages], [[secs(t[k]) for k in stages]]), ""]

    pics = pictures(img_dir, md_dir, name)
    for rest, rel in pics:
        lines += [f"![{name} {rest}]({rel})", "", f"_{caption(rest)}_ (`{rel}`)", ""]
    if not pics:
        lines += ["_No pictures (run `make report`)._", ""]
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out_dir", nargs="?", type=pathlib.Path, default=pathlib.Path("out"))
    ap.add_argument("--img", type=pathlib.Path, default=pathlib.Path("docs/img"))
    ap.add_argument("--md", type=pathlib.Path, default=pathlib.Path("docs/results.md"))
    args = ap.parse_args()
    runs = load_runs(args.out_dir)
    pictures.names = list(runs)
    md_dir = args.md.parent
    md_dir.mkdir(parents=True, exist_ok=True)

    lines = ["# Results", "",
             f"Made by `make report` on {datetime.date.today().isoformat()} from the run folders under "
             f"`{args.out_dir}/` (`pipelines/results.py`); pictures by `pipelines/report.py` in "
             f"`{os.path.relpath(args.img, md_dir)}/`. Lengths, forces and stresses are in each scene's units; "
             "times are wall-clock seconds on the machine that ran `make examples`.", ""]

    lines += ["## The paper's examples against its tables", ""]
    for spec in PAPER_TABLES:
        lines += paper_table(spec, runs)

    lines += ["### Example 3 — vault on quasi-rigid blocks (the paper's Tables 3 and 4)", ""]
    found = False
    for t in ["table3.md", "table4.md"]:
        f = args.out_dir / "vault" / t
        if f.exists():
            found = True
            body = [("###" + ln) if ln.startswith("#") else ln for ln in f.read_text().strip().splitlines()]
            lines += [f"From `{f}` (`pipelines/vault_table.py`, `make vault`):", ""] + body + [""]
    if not found:
        lines += [f"_Not available: `{args.out_dir}/vault/table3.md` and `table4.md` are made by "
                  "`pipelines/vault_table.py`._", ""]

    lines += ["## Section stresses along the contact iterations", "",
              "Interior stresses, and so `sections/<name>.csv`, are those of the final state; with "
              "`history = \"full\"` sgbem also writes `sections/<name>_path.csv`, the section at every "
              "contact iteration, which the pictures of the paper's Figs. 5 and 6 use. "
              "`pipelines/somigliana.py` evaluates the same stresses independently from each archived "
              "state's boundary displacements and tractions (Somigliana's identity, no body forces): "
              "the pictures print the difference (about 1e-11 of the largest stress inside, up to 1e-2 "
              "at the point next to the boundary, where sgbem corrects the boundary layer), and runs "
              "without a `_path.csv` fall back to it.", ""]

    lines += ["## Every run", ""]
    order = [r for spec in PAPER_TABLES for r in spec["runs"] if r in runs]
    order += [r for r in runs if r.startswith("vault") and r not in order]
    order += [r for r in runs if r not in order]
    for name in order:
        path, s = runs[name]
        lines += run_section(name, path, s, args.img, md_dir)

    args.md.write_text("\n".join(lines).rstrip() + "\n")
    print(f"results: {args.md}: {len(runs)} runs")


if __name__ == "__main__":
    sys.exit(main())
