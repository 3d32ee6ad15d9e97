"""Run a whole validation study from one TOML file (see ``data/smart_beam/study.toml``).

``mvtk.study.run(study_path, out_dir)`` chains ingest -> FE -> damping -> updating ->
(optional Monte-Carlo uncertainty of the updated model, ``[uncertainty]``) ->
Craig-Bampton SE -> controllers -> HTML report, caching each stage in ``out_dir/cache``
under a key derived from what the stage read (verified on load; see docs/study.md).
``SCHEMA`` is the one declarative schema of the study file, used by every command.
"""

from ._config import Study, load_study
from ._init import InitResult, init_study
from ._report import study_checks
from ._run import STAGES, StudyResult, run
from ._schema import CONTROLLER_SCHEMAS, SCHEMA, Key, Table

__all__ = ["Study", "StudyResult", "STAGES", "SCHEMA", "CONTROLLER_SCHEMAS", "Key", "Table",
           "load_study", "run", "study_checks", "init_study", "InitResult"]
