# `snakemake converge`: a map you can trust within a budget. The run starts with `converge.start`
# LDS cases, then adds batches (chosen where the model is least sure about the maps, or the next
# LDS points) until the map criteria of `converge.stop_on` hold, or the case / CPU budget is spent.
# Each step is a checkpoint: `snakemake -n converge` shows the first stage (the LDS start), and the
# batch after a step is known only once that step has run. Every finished case is re-used.


def converge_chain(n):
    """(case ids of the run's first n cases, the step before n or None), following the steps."""
    start = GROW.get("start", 32)
    preset = SWEEPS.get("lds", {}).get("preset")
    ids, m, prev = list(lds_case_ids(start)), start, None
    while m < n:
        with open(checkpoints.converge_step.get(n=m).output.step) as fh:
            step = json.load(fh)
        if step["stop"] or step["next_n"] is None:
            raise WorkflowError(f"spreadmap: converge step {m} stopped ({step['reason']}); no step {n}")
        ids += [add_case(point, preset=preset) for point in step["next_batch"]]
        prev, m = m, step["next_n"]
    if m != n:
        raise WorkflowError(f"spreadmap: no converge step at {n} cases (the steps run {start}, ..., {m})")
    return ids, prev


def converge_step_input(wildcards):
    ids, prev = converge_chain(int(wildcards.n))
    out = {"metrics": [f"results/cases/{cid}/metrics.json" for cid in ids]}
    if prev is not None:
        out["previous"] = f"results/converge/step_{prev}.json"
    return out


def converge_final_step(wildcards):
    """Follow the converge checkpoints from the LDS start to the step that stopped."""
    n = GROW.get("start", 32)
    while True:
        with open(checkpoints.converge_step.get(n=n).output.step) as fh:
            step = json.load(fh)
        if step["stop"]:
            return f"results/converge/step_{n}.json"
        n = step["next_n"]


checkpoint converge_step:
    input:
        unpack(converge_step_input),
    output:
        step="results/converge/step_{n}.json",
    params:
        converge=GROW,
        tolerance=CONV.get("tolerance", 0.005),
        floors=CONV.get("floors"),
        ranges=RANGES,
        maps=config.get("maps", {}),
        lds_seed=SWEEPS.get("lds", {}).get("seed", 42),
    wildcard_constraints:
        n=r"\d+",
    log:
        "logs/converge/step_{n}.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/converge_step.py"


rule converge:
    """Where the run stopped and why: the criteria, the batch at which each held, the path; and
    the run's results table."""
    input:
        converge_final_step,
        "results/converge/table.csv",
    output:
        stopped="results/converge/stopped.json",
        summary="results/converge/summary.txt",
        path=report("results/converge/path.png", caption="captions/converge_path.rst", category="Convergence"),
    log:
        "logs/converge/stopped.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/converge_summary.py"


def converge_final_cases():
    """Case ids of the whole converge run, in run order, with the batch each came in and
    whether it is an LDS case (the start and each batch's LDS share) or an active one."""
    final = converge_final_step(None)
    n = int(final.rsplit("_", 1)[1].split(".")[0])
    ids, _ = converge_chain(n)
    with open(final) as fh:
        is_lds = json.load(fh)["is_lds"]
    start, batch = GROW.get("start", 32), GROW.get("batch", 16)
    return [(cid, 0 if i < start else 1 + (i - start) // batch, bool(is_lds[i])) for i, cid in enumerate(ids)]


rule converge_table:
    """The results table of the converge run (every case, in run order, its batch): what a
    surrogate and the maps trained on the converged sample read."""
    input:
        step=converge_final_step,
        metrics=lambda wc: [f"results/cases/{cid}/metrics.json" for cid, _, _ in converge_final_cases()],
        benchmarks=lambda wc: [f"results/cases/{cid}/benchmark.tsv" for cid, _, _ in converge_final_cases()],
    output:
        table="results/converge/table.csv",
    params:
        labels=lambda wc: [{"sweep": "converge", "index": i, "batch": b, "lds": lds}
                           for i, (_, b, lds) in enumerate(converge_final_cases())],
    log:
        "logs/converge/table.log",
    localrule: True
    conda:
        "../envs/analysis.yaml"
    script:
        "../scripts/results_table.py"
