"""Types of :mod:`rvmsim`'s lazily imported names (``rvmsim/__init__.py``'s ``_LAZY``;
``tests/test_api.py`` checks the two agree)."""

from ._version import __version__ as __version__
from .errors import (
    CriteriaError as CriteriaError,
    InputFileError as InputFileError,
    ParamsFileError as ParamsFileError,
    RvmsimError as RvmsimError,
    SceneError as SceneError,
    SweepFileError as SweepFileError,
    TuningConfigError as TuningConfigError,
    VariationError as VariationError,
)
from .batch import (
    load_sweep as load_sweep,
    run_sweep as run_sweep,
)
from .camera import (
    FisheyeCamera as FisheyeCamera,
    rotation_from_ypr as rotation_from_ypr,
)
from .criteria import (
    Criteria as Criteria,
    EcResult as EcResult,
    evaluate as evaluate,
    load_criteria as load_criteria,
    default_criteria as default_criteria,
)
from .eol import (
    run_station as run_station,
    StationSettings as StationSettings,
)
from .isp import (
    IspParams as IspParams,
    OutputSpec as OutputSpec,
    process as process,
    load_params as load_params,
)
from .pipeline import (
    RvmFrame as RvmFrame,
    evaluate_params as evaluate_params,
    render_rvm as render_rvm,
    make_evaluator as make_evaluator,
)
from .render import (
    FisheyeImages as FisheyeImages,
    render_fisheye as render_fisheye,
    cached_render as cached_render,
)
from .report import (
    write_report as write_report,
)
from .robust import (
    load_variation as load_variation,
    draw_samples as draw_samples,
    robustness as robustness,
    RobustnessSettings as RobustnessSettings,
)
from .runs import (
    RunStore as RunStore,
)
from .scene import (
    Scene as Scene,
    load_scene as load_scene,
    scene_from_dict as scene_from_dict,
)
from .search import (
    TuningConfig as TuningConfig,
    load_tuning_config as load_tuning_config,
    STRATEGIES as STRATEGIES,
)
from .tune import (
    tune as tune_scene,
    TuneRequest as TuneRequest,
    RunOptions as RunOptions,
    resume as resume_run,
)
from .pose import load_capture as load_capture
from .validate import validate as validate_capture

__all__: list[str]
