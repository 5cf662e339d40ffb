"""Ground motions: recorded ones, Rezaeian & Der Kiureghian models (plain and spectrum-matched), bands, spectra."""

from housner.scenarios.motions.build import build_motions
from housner.scenarios.motions.elastic import response_spectrum
from housner.scenarios.motions.rdk import fit, simulate_motions
from housner.scenarios.motions.rdk_match import MatchedRDK, fit_matched, simulate_matched
from housner.scenarios.motions.rdk_params import RDKParams
from housner.scenarios.motions.records import elcentro, load_record

__all__ = [
    "MatchedRDK",
    "RDKParams",
    "build_motions",
    "elcentro",
    "fit",
    "fit_matched",
    "load_record",
    "response_spectrum",
    "simulate_matched",
    "simulate_motions",
]
