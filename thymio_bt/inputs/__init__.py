"""What users type, read and checked: files read with caps (:mod:`.reading`), YAML that remembers
lines (:mod:`.yamlio`), values with units (:mod:`.units`, :mod:`.fields`), and pydantic errors turned
into located problems (:mod:`.validation`)."""
