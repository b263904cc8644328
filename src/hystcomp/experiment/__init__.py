"""The paper's experiment: references, tracking runs, metrics, tables and figures."""
