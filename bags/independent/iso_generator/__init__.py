"""An independent generator of tracker exports for metrocell's diagnose, written from the
standards' definitions (ISO 230-1 geometric errors, ISO 230-2 positioning and reversal,
ISO 230-3 thermal effects) and from how a laser tracker measures (azimuth, elevation and an
ADM range computed with the refractive index of the air it was given).

Nothing here reads metrocell's code or its twin: the machine's errors, the tracker and the
programs are written from those definitions (numpy only). One idea per module:

    air.py              refractive index of air (Birch & Downs 1994 modified Edlén)
    geometric_errors.py ISO 230-1 errors of linear axes (positioning, straightness, squareness,
                        periodic ball-screw error) as the tool-to-workpiece displacement
    reversal.py         ISO 230-2 reversal value B (signed) and the approach directions
    thermal.py          ISO 230-3: scale expansion, structural growth lagging its sensor
    temperatures.py     temperature and station-air histories over a shift
    tracker.py          the laser tracker: its pose on the table, spherical measurement,
                        range errors (warm-up, refraction), pose drift, noise and U95
    programs.py         measurement programs: point sets, visiting orders, timing, sweeps
    serial_arm.py       UR5 forward kinematics from the published DH table
    linear_delta.py     linear delta kinematics (rod lengths, tower radius, tower angles)
    export.py           the CSV export, its mapping file and the user's model file
    cases.py            the case table: what each recording conceals
"""
