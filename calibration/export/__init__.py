"""Hand-over of a calibrated material to other DEM codes (issue 30).

``material``: the plain-data material the exporters read (``ExportMaterial``); ``conversions``: the
unit and convention conversions, one pure function each; ``liggghts``: the LIGGGHTS-PUBLIC 3.8.0
input include; ``verify``: runs the include in LIGGGHTS on the screening rig and compares with
demcal's own lab (the proof that the hand-over holds).
"""
