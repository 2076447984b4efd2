"""The published study (docs/study).

cases      the study's sweeps as planned by a configuration, and the table of its finished cases
summary    docs/study/summary.md: the study's questions answered from its published files
restore    finished cases restored from a published cases table into a workflow directory
checksums  the SHA256SUMS manifests of published folders, and reading a file only if it matches
"""
