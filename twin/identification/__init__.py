"""Clearance identification from a bench recording (``twin identify``).

* :mod:`twin.identification.features`: window features of the calibrated accelerations in the crank-angle
  domain (order tracking with the encoder), bands, impacts and shape statistics;
* :mod:`twin.identification.inputs`: what the model reads: a recording's calibrated accelerations and encoder
  counts, the same from a simulated run, a dataset's window features (one dataset or several pooled);
* :mod:`twin.identification.model`: the model (fault location, clearance size with a 90 % interval), its file,
  and the answer for a recording (:func:`~twin.identification.model.identify_recording`);
* :mod:`twin.identification.results`: the answer as typed values (``IdentifyResult``, a ``JointAnswer`` per
  clearance location), with ``to_dict()`` and ``to_json()``;
* :mod:`twin.identification.intervals`: the conformal 90 % intervals, their calibration and the held-out size
  accuracy;
* :mod:`twin.identification.training`: training on ``twin dataset`` folders (``train``, ``TrainOptions``);
* :mod:`twin.identification.trees`: the gradient-boosted trees as plain arrays (exported from scikit-learn,
  answered with numpy);
* :mod:`twin.identification.modelfile`: the model file (an ``.npz`` of plain arrays and JSON, no pickle);
* :mod:`twin.identification.evaluate`: confusion matrix, recall, size errors and interval coverage on a
  dataset;
* :mod:`twin.identification.restitution`: S001's restitution sweep against a recording.
"""
