"""Readers of files, converted once to SI here: measured data with units in headers and CSV columns
(:mod:`~housner.readers.measured_data`) and ground-motion record files, PEER AT2 and the motion CSV
(:mod:`~housner.readers.motion_files`)."""
