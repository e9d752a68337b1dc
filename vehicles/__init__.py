"""Vehicle kinds: one room each (``vehicles/<kind>/``) behind :class:`vehicles.kind.VehicleKind`.

The registry maps a show file's ``kind`` to its room, imported only when first asked for (a room
may pull in MuJoCo or CasADi).
"""
