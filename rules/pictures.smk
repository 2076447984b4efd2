PICTURES = config["pictures"]
NAMED = {label["name"]: cid for cid, label in SETS.get("points", [])}


rule case_picture:
    """Side and top views of one named case at blade start, window middle and window end."""
    input:
        raw=lambda wc: f"results/cases/{NAMED[wc.name]}/raw.json",
    output:
        report("results/pictures/{name}.png", caption="captions/case_picture.rst", category="Cases",
               subcategory="{name}"),
    params:
        colour_by=PICTURES["colour_by"],
    log:
        "logs/pictures/{name}.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/case_picture.py"


rule case_vtk:
    """Legacy VTK files of a named case's snapshots, for ParaView."""
    input:
        raw=lambda wc: f"results/cases/{NAMED[wc.name]}/raw.json",
    output:
        directory("results/vtk/{name}"),
    log:
        "logs/vtk/{name}.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/case_vtk.py"
