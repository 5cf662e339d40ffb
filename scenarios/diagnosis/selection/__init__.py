"""Which effect is missing: the folds and their scorers, the fits, a candidate's trial and the forward selection
that builds the error ladder."""
