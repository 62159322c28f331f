"""What users type, read and checked: files read with caps (:mod:`.reading`), YAML that remembers
lines (:mod:`.yamlio`), values with units (:mod:`.units`, :mod:`.fields`), and pydantic errors turned
into located problems (:mod:`.validation`).

Example::

    >>> from thymio_bt.inputs.units import parse_value
    >>> parse_value("10cm/s")
    Quantity(value=0.1, kind='speed')
"""
