"""Reports: HTML pages of runs, studies and diagnoses, their figures, and tolerance assertions for pytest."""

if __name__ != "housner.reports":  # this folder imported by its 0.1 name from a checkout
    from housner._legacy import become

    become(__name__)
