"""Many clips converted at once: the per-clip job and the executors that run it.

:mod:`vidcap.batch.job` is the work for one clip, a plain function. The executors
only schedule it: :mod:`vidcap.batch.local` on a process pool of this machine,
:mod:`vidcap.batch.cluster` on a Dask ``distributed`` cluster. ``vidcap batch``
(:mod:`vidcap.commands.batch`) plans the outputs, picks an executor and writes the
summary, so both paths behave the same.
"""
