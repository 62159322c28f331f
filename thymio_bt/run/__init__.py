"""Running missions: one run's tick loop (:mod:`.runner`), what it produced (:mod:`.result`), its
phases (:mod:`.phases`), signals (:mod:`.interrupts`), and many runs at once (:mod:`.sweep`,
:mod:`.matrix`, :mod:`.distributed`)."""
