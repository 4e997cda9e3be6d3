"""Clearance identification from a bench recording (``twin identify``).

* :mod:`twin.identification.features`: window features of the calibrated accelerations in the crank-angle
  domain (order tracking with the encoder), bands, impacts and shape statistics;
* :mod:`twin.identification.model`: the gradient-boosting model (fault location, clearance size with a
  90 % interval), training on a ``twin dataset``, identification of a recording;
* :mod:`twin.identification.trees`: the gradient-boosted trees as plain arrays (exported from scikit-learn,
  answered with numpy);
* :mod:`twin.identification.modelfile`: the model file (an ``.npz`` of plain arrays and JSON, no pickle);
* :mod:`twin.identification.evaluate`: confusion matrix, recall, size errors and interval coverage on a
  dataset.
"""
