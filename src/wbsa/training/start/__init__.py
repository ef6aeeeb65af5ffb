"""The body fit's learned start (``wbsa train-start``): crops of ``wbsa train``'s captures and a small CNN on them.

``settings``  :class:`StartSettings`: bodies, captures, training, seed
``data``      the crops and their truth, one ``.npz`` per chunk of bodies (:func:`start_crops`, resumable)
``fit``       the network's training (:func:`fit_start`) and the figures it is judged by
``run``       :func:`train_start`: crops → network → validation figures → ``start.npz`` and its card
``command``   ``wbsa train-start``

The network and the crop live with the body fit (:mod:`wbsa.estimation.methods.body_fit.start_net`,
:mod:`~wbsa.estimation.methods.body_fit.start_crop`), which will read them at run time.
"""
