"""One DEM case, from design point to files.

identity    case identity: the content key, the case id, the scene of a point (case_scene, case_id)
scene       every number of a case derived from its point, preset and configuration
render      the YADE scene template rendered into one self-contained script per case
launcher    a rendered case run with Debian's YADE, kept away from the venv; its failure records
substrate   the floor a case is spread on (flat or rough), and the effective gap over it
migrate     case folders named before content keys renamed to their content ids
pictures    pictures of one case: the powder bed, the blade and the deposit at a few moments
vtk_export  a case's sphere snapshots as legacy VTK files, for ParaView
"""
