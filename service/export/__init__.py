"""Exports of a calibrated material: the neutral material card (``card``), the formats written from it
(``formats``), the database views they are built from (``store``) and the shareable HTML report
(``report_html``)."""
