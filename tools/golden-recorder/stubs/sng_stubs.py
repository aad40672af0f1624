"""Install minimal stand-ins for torch / dgl / the SNGNN sub-package so that socnavgym 0.1.1
can be imported and run with the DSRNN reward without PyTorch/DGL.  socnavgym imports them at import
time and RewardAPI.__init__ constructs a SocNavAPI object (SNGNN model) for every reward, but the
DSRNN reward never calls it.  None of the stubbed code touches Python's `random` or numpy's RNG."""
import sys, types, contextlib

def install():
    if 'torch' not in sys.modules:
        torch = types.ModuleType('torch')
        torch.__stub__ = True
        cuda = types.ModuleType('torch.cuda')
        cuda.is_available = lambda: False
        torch.cuda = cuda
        torch.no_grad = contextlib.nullcontext
        torch.device = lambda *a, **k: ('device', a)
        torch.set_num_threads = lambda n: None
        sys.modules['torch'] = torch
        sys.modules['torch.cuda'] = cuda
    if 'dgl' not in sys.modules:
        dgl = types.ModuleType('dgl'); dgl.__stub__ = True
        sys.modules['dgl'] = dgl
    pkg = 'socnavgym.envs.utils.sngnnv2'
    if pkg not in sys.modules:
        m = types.ModuleType(pkg); m.__path__ = []; m.__stub__ = True
        class SocNavAPI:
            def __init__(self, *a, **k):
                self.stub = True
            def predictOneGraph(self, *a, **k):
                raise RuntimeError('SNGNN is stubbed out (no torch/dgl): DSRNN configs only')
        class _Dummy:
            def __init__(self, *a, **k):
                raise RuntimeError('SNGNN is stubbed out (no torch/dgl): DSRNN configs only')
        sub1 = types.ModuleType(pkg + '.socnav'); sub1.SocNavDataset = _Dummy
        sub2 = types.ModuleType(pkg + '.socnav_V2_API')
        sub2.Human = _Dummy; sub2.Object = _Dummy; sub2.SNScenario = _Dummy; sub2.SocNavAPI = SocNavAPI
        for name in ('SocNavDataset',):
            setattr(m, name, _Dummy)
        m.otherHuman = _Dummy; m.otherObject = _Dummy; m.SNScenario = _Dummy; m.SocNavAPI = SocNavAPI
        m.socnav = sub1; m.socnav_V2_API = sub2
        sys.modules[pkg] = m; sys.modules[pkg + '.socnav'] = sub1; sys.modules[pkg + '.socnav_V2_API'] = sub2
