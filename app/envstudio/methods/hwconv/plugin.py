"""Plugin ``hwconv``: seed 004 §5.2 (Kautz, Vázquez, Heidrich, Seidel; EGWR, June 2000)."""

from envstudio.methods.hwconv import commands, figures
from envstudio.methods.hwconv.method import HwConvMethod
from envstudio.plugin import Plugin

PLUGIN = Plugin(
    HwConvMethod,
    order=2000.06,
    figures=(figures.DISTORTION,),
    bench_tables=(commands.TABLE, commands.ACCURACY),
)
