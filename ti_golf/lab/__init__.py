"""The lab application (report §2.2 and §2.4): :class:`~ti_golf.lab.app.Lab`, the logic a window
drives (and tests drive headless), and ``ti-golf lab``'s GGUI window (:mod:`ti_golf.lab.window`)."""
