"""Running missions: one run's tick loop (:mod:`.runner`), its phases (:mod:`.phases`), signals
(:mod:`.interrupts`), and many runs at once (:mod:`.sweep`, :mod:`.matrix`, :mod:`.distributed`)."""
