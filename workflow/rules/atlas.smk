# The fault atlas: one coarse capacity map per (locked joint, lock angle), then the atlas table.
#   snakemake --cores 2 atlas
ATLAS_SLICES = atlas_slices(DOC)
ATLAS_CASES = RUN.atlas.cases if RUN.atlas else []  # (joint, angle label)
ATLAS_DIRS = [f"results/atlas/joint{j}_angle{a}" for j, a in ATLAS_CASES]


rule atlas_map:
    """Capacity map with joint {joint} locked at {angle} deg, and its summary per task payload."""
    input:
        robot=config["robot"],
    output:
        voxels="results/atlas/joint{joint}_angle{angle}/voxels.parquet",
        summary="results/atlas/joint{joint}_angle{angle}/summary.parquet",
    params:
        slice=with_code(canonical(ATLAS_SLICES.get("map", {})), "atlas_map"),
    log:
        "results/logs/atlas/joint{joint}_angle{angle}.log",
    wildcard_constraints:
        joint=r"\d+",
        angle=r"-?\d+(\.\d+)?",
    script:
        "../scripts/atlas_map.py"


rule atlas_tables:
    """The atlas table, the capacity-volume curves and their figures."""
    input:
        summaries=[f"{d}/summary.parquet" for d in ATLAS_DIRS],
        voxels=[f"{d}/voxels.parquet" for d in ATLAS_DIRS],
    output:
        atlas="results/atlas/atlas.parquet",
        curves="results/atlas/curves.parquet",
        heatmap=report("results/atlas/heatmap.png", category="Fault atlas", caption="../report/atlas_heatmap.rst"),
        curves_png=report("results/atlas/curves.png", category="Fault atlas", caption="../report/atlas_curves.rst"),
    params:
        slice=with_code(canonical(ATLAS_SLICES.get("atlas", {})), "atlas"),
    log:
        "results/logs/atlas/atlas.log",
    script:
        "../scripts/atlas.py"


rule atlas_catalogue:
    """Catalogue of the atlas datasets."""
    input:
        [f"{d}/{name}.parquet" for d in ATLAS_DIRS for name in ("voxels", "summary")],
        "results/atlas/atlas.parquet",
        "results/atlas/curves.parquet",
    output:
        "results/atlas/catalogue.parquet",
    params:
        code=with_code("{}", "catalogue"),
    log:
        "results/logs/atlas/catalogue.log",
    script:
        "../scripts/catalogue.py"


rule atlas:
    """Target: the fault atlas of the config's atlas section."""
    input:
        "results/atlas/atlas.parquet",
        "results/atlas/heatmap.png",
        "results/atlas/curves.png",
        "results/atlas/catalogue.parquet",
