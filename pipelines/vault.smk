# The vault's cohesion sweep (the paper's example 3) as a Snakemake workflow: the generic
# pipelines/Snakefile on pipelines/sweeps/vault.toml (one job per cohesion, sweep.csv and
# sweep.md), then the paper's tables out/vault/table3.md and table4.md, as `make vault`.
#
#   snakemake -s pipelines/vault.smk --cores 2      (after `make build mesh`)
#   on SLURM: as pipelines/Snakefile says, with -s pipelines/vault.smk

config.setdefault("sweep", "pipelines/sweeps/vault.toml")


localrules:
    vault,
    vault_tables,


rule vault:
    default_target: True
    input:
        "out/vault/table3.md",
        "out/vault/table4.md",


include: "Snakefile"


if os.path.normpath(OUT) != os.path.join("out", "vault", "sweep"):
    raise WorkflowError("pipelines/vault.smk: the vault's points live in out/vault/sweep")


rule vault_tables:
    input:
        rules.table.output,
    output:
        "out/vault/table3.md",
        "out/vault/table4.md",
    shell:
        "python3 pipelines/vault_table.py out"
