"""The block under analytical pulses: the pulses themselves, Ricker wavelets, one-sine pulses and free-vibration
releases (:mod:`~housner.pulse_response.pulses`), and the rocking spectra they give (seed Figure 2,
:mod:`~housner.pulse_response.spectra`)."""
