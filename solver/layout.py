"""What a run records, slot by slot: the history's columns (`H_…`), the extremes it reports
(`X_…`) and its energy terms (`E_…`). The kernel writes them; the controller, the lumped model,
the summary and the limits read them. No Numba here: reading a layout loads no kernel."""

from __future__ import annotations

import numpy as np

# History quantities: `history[H_…, k]` is the k-th kept layer's (one contiguous series each)
H_TIME, H_STRIKER_DISP, H_STRIKER_VEL, H_STRUCK_END, H_WORKING_END = 0, 1, 2, 3, 4
H_CONTACT_FORCE, H_OVERLAP, H_MEDIUM_FORCE, H_EXTERNAL_FORCE = 5, 6, 7, 8
H_EXTERNAL_WORK, H_DISSIPATED_CONTACT, H_DISSIPATED_MEDIUM = 9, 10, 11
H_STRIKER_KINETIC, H_TOOL_KINETIC, H_TOOL_STRAIN, H_CONTACT_POTENTIAL, H_MEDIUM_POTENTIAL = (12, 13, 14, 15, 16)
H_MEDIUM_PLASTIC, H_PERMANENT_PENETRATION, H_STRIKER_STRAIN = 17, 18, 19
H_ANVIL_DISP, H_ANVIL_VEL, H_ANVIL_FORCE, H_ANVIL_KINETIC = 20, 21, 22, 23  # its force on the tool
H_LAUNCHED, H_WITHDRAWN = 24, 25  # blow after blow: `E_LAUNCHED`, `E_WITHDRAWN` so far
H_TO_SHAFT = 26  # `E_TO_SHAFT` so far
H_TRANSFERRED = 27  # the work done on the tool through its struck end in this blow
H_BETWEEN_BLOWS = 28  # a hammer at work: `E_BETWEEN_BLOWS` so far
HISTORY_COLUMNS = 29

# Extreme slots (`extremes[X_…]`): what a run reports beyond its recordings, kept up to date
X_PEAK_FORCE, X_PEAK_FORCE_TIME = 0, 1
X_MAX_COMPRESSION, X_MAX_COMPRESSION_X, X_MAX_COMPRESSION_TIME = 2, 3, 4
X_MAX_TENSION, X_MAX_TENSION_X, X_MAX_TENSION_TIME = 5, 6, 7
# A peak stress with where and when it was: (value, x, time)
COMPRESSION = (X_MAX_COMPRESSION, X_MAX_COMPRESSION_X, X_MAX_COMPRESSION_TIME)
TENSION = (X_MAX_TENSION, X_MAX_TENSION_X, X_MAX_TENSION_TIME)
X_CONTACTS = 8  # finished contact intervals
X_CO_IMPACT, X_REBOUND_VELOCITY = 9, 10  # when the first contact ended, the striker's velocity then
X_ENERGY_EXCESS = 11  # max over time of (stored + dissipated − input): > 0 means energy created
X_FAILED_TIME = 12
X_MIN_CONTACT_STEPS = 13  # fewest steps any finished contact interval was resolved by
X_MAX_PENETRATION = 14  # the working end's deepest penetration into the medium
X_MAX_TRANSFERRED = 15  # the most work done on the tool through its struck end (EMX)
X_SET = 16  # the medium's permanent penetration where the blow's duration ends
# How long the overlap took, where the first contact ended, to cross the rounding of the
# displacements (`GRAZING`) at the rate it fell then: next to nothing where the faces part; where a
# contact fades out, held by a link that relaxes slowly, of the order of that link's time, and
# rounding then sets the contact's end
X_FADE_TIME = 17
EXTREME_SLOTS = 18

# An overlap within this fraction of the ends' displacements is rounding: it changes no contact
GRAZING = 1e-12

# Energy slots (`energy[0, …]` at the last layer, `energy[1, …]` at the one before): running work
# and dissipation, and the stored terms
E_EXTERNAL_WORK, E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM = 0, 1, 2
E_STRIKER_KINETIC, E_TOOL_KINETIC, E_TOOL_STRAIN, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL = (3, 4, 5, 6, 7)
E_MEDIUM_PLASTIC = 8  # the medium's work into permanent penetration
E_STRIKER_STRAIN = 9  # an elastic striker's
# Blow after blow: the strikers (and anvils) launched after the first, and what each had left
# when withdrawn
E_LAUNCHED, E_WITHDRAWN = 10, 11
E_ANVIL_KINETIC = 12
E_TO_SHAFT = 13  # the net work done on the soil along the tool's side (`shaft`)
# Under gravity: the weights' work since impact, and what the tool, the medium and the contacts
# stored at rest before it (`solver.rest`), with the medium's share
E_GRAVITY_WORK, E_STORED_AT_REST, E_MEDIUM_AT_REST = 14, 15, 16
E_BETWEEN_BLOWS = 17  # a hammer at work: what the tool's leftover waves held when it came to rest
ENERGY_SLOTS = 18


# The tool's stretches of equal length over which its greatest stresses are kept apart (the stress
# envelope): node i of N lies in stretch ⌊i·ENVELOPE_BINS/N⌋, the working end in the last.
ENVELOPE_BINS = 8


def new_extremes() -> np.ndarray:
    """The extremes before a run: none yet (NaN where nothing may happen)."""
    x = np.zeros(EXTREME_SLOTS)
    x[X_CO_IMPACT] = np.nan
    x[X_REBOUND_VELOCITY] = np.nan
    x[X_FADE_TIME] = np.nan
    x[X_FAILED_TIME] = np.nan
    x[X_MIN_CONTACT_STEPS] = np.inf
    x[X_MAX_PENETRATION] = -np.inf
    return x
