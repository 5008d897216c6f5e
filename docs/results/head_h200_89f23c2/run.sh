#!/bin/bash
# The runs of this folder, from the project root on a host with a GPU: steps (bench, bench_q, graphs,
# ev:<robot>:<benchmark>) run in order until DEADLINE seconds have passed, a step done in an earlier call skipped;
# each step's files land in /tmp/res, tarred to $OUT_DIR/res.tar.gz after each step.
DEADLINE=${DEADLINE:-500}
OUT_DIR=${OUT_DIR:-rescore_out}
start=$SECONDS
export PYTHONUNBUFFERED=1
mkdir -p /tmp/res /tmp/ev "$OUT_DIR"
py=python
step() {  # name, command...
  local name=$1; shift
  if [ -e /tmp/res/$name.done ]; then return; fi
  local left=$((DEADLINE - (SECONDS - start)))
  if [ $left -lt 60 ]; then echo "skip $name ($left s left)"; return; fi
  echo "=== $name (left $left s) at $(date +%T)"
  local t0=$SECONDS
  timeout $left "$@" > /tmp/res/$name.log 2>&1
  local rc=$?
  echo "rc $rc wall $((SECONDS - t0)) s" >> /tmp/res/$name.log
  tail -n 12 /tmp/res/$name.log
  [ $rc -eq 0 ] && touch /tmp/res/$name.done
  tar czf "$OUT_DIR/res.tar.gz" -C /tmp res
}
ev() {  # robot benchmark
  local task=gente_$1 b=$2
  step ev_${b}_$1 bash -c "$py -m legged_gente.scripts.evaluate --task $task --pretrained --benchmark $b --robots_per_terrain 64 --seed 0 --out /tmp/ev/${b}_$1 --no_progress && cp /tmp/ev/${b}_$1/report.csv /tmp/res/${b}_$1.csv && cp /tmp/ev/${b}_$1/report.json /tmp/res/${b}_$1.json"
}
nvidia-smi --query-gpu=name --format=csv,noheader
git rev-parse HEAD 2>/dev/null
for s in "$@"; do
  case $s in
    bench) step bench_biped $py -m legged_gente.scripts.benchmark --task gente_biped --num_envs 4096 8192 16384 --check_sync --csv /tmp/res/bench_biped.csv ;;
    bench_q) step bench_quadruped $py -m legged_gente.scripts.benchmark --task gente_quadruped --num_envs 8192 --check_sync --csv /tmp/res/bench_quadruped.csv ;;
    prof) step profile_4096 $py tools/profile_force_kernels.py --task gente_biped --num_envs 4096 ;;
    prof_q) step profile_q_4096 $py tools/profile_force_kernels.py --task gente_quadruped --num_envs 4096 ;;
    b4096_*) step $s bash -c "$py -c 'import legged_gente; print(legged_gente.__file__)' && $py -m legged_gente.scripts.benchmark --task gente_biped --num_envs 4096 --iterations 0 --csv /tmp/res/$s.csv" ;;
    base4096_*) step $s bash -c "cd ab_base && $py -c 'import legged_gente; print(legged_gente.__file__)' && $py -m legged_gente.scripts.benchmark --task gente_biped --num_envs 4096 --iterations 0 --csv /tmp/res/$s.csv" ;;
    graphs) step check_cuda_graphs_biped $py tools/check_cuda_graphs.py --task gente_biped --env_only ;;
    ev:*) IFS=: read -r _ robot b <<< "$s"; ev $robot $b ;;
  esac
done
ls /tmp/res
