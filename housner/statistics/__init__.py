"""Statistics on ensembles of rocking responses: distributions of theta_max/alpha with overturning as an outcome of
its own (:mod:`~housner.statistics.ensemble_stats`), and the probability of overturning as a binomial proportion
with its interval (:mod:`~housner.statistics.proportions`)."""
