"""Reports: HTML pages of runs, studies and diagnoses, their figures, and tolerance assertions for pytest."""

if __name__ != "housner.reports":  # this folder imported by its own name, from a checkout's root
    raise ImportError(f"`{__name__}` is not an import name of this project: import `housner.reports`")
