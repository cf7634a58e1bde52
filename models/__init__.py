"""Case-study models: plants, controllers, task programs, metrics and reports registered by name.

Every module of this package is imported by :func:`netsim.registry.load_plugins` (``models`` is one of
:data:`netsim.registry.PLUGIN_MODULES`), so a case study is a module or package here plus its ``@register``
lines: nothing has to be listed in this file.
"""
