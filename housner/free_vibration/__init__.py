"""Free rocking: its closed forms (:mod:`~housner.free_vibration.closed_forms`), the impacts and peaks of a sampled
rotation (:mod:`~housner.free_vibration.impacts`) and the calibration of p and r from free vibrations
(:mod:`~housner.free_vibration.calibration`)."""
