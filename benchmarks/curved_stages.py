"""Stage times of a `curvefem mesh` report.json shared by the curved-meshing benchmarks."""


def coarsening_seconds(rep):
    """The coarsening with every attempt it took: the time_s stages coarsen, coarsen (linear
    phase), repair, repair (failed) and each discarded attempt N (a discarded attempt's curving
    and checks included). report.json's stages do not overlap (since cf2f4f1)."""
    t = (rep or {}).get("time_s", {})
    keys = [k for k in t if k.startswith("coarsen") or k.startswith("repair")
            or k.startswith("discarded attempt")]
    return sum(t[k] for k in keys) if keys else None
