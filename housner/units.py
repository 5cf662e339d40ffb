"""Physical constants; SI units everywhere inside the suite."""

#: Standard gravity [m/s^2]; AT2 records in g are converted with it, once, in the reader.
G = 9.80665
