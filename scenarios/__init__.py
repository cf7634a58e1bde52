"""The shipped scenario and sweep files (YAML), installed as package data ``netsim.scenarios``.

No code lives here: this file only makes the folder a package that :mod:`importlib.resources` finds in
editable and wheel installs alike. Look scenarios up by name with :mod:`netsim.shipped`
(``netsim run dc_servo_can``, ``netsim scenarios``).
"""
