"""Reports: statistics tables, figures, HTML pages and tolerance assertions for pytest."""
