"""The renderers of benchmarks/report.py's blocks, one module per topic; each module's ``__all__``
names its blocks."""
