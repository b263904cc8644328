"""The paper's experiment: comparison runs, metrics, tables and figures."""
