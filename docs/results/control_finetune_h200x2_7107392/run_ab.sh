#!/bin/bash
# Two fine-tunes of the shipped biped side by side, one per GPU, to separate the mosaic columns' effect:
#   C  the mosaic fine-tune's recipe without the mosaic columns (20 columns, 4096 robots)
#   K  the mosaic fine-tune's 24 columns with each column's robots kept (4915 robots: 204.8 a column, as 4096 on 20)
# Both: critic warm-up 500, start rows 0-8, the shipped fine-tune's other settings.
#   bash run_ab.sh train <minutes> <iterations>          from the shipped policy (--pretrained)
#   bash run_ab.sh resume <minutes> <total iterations>   continue each run in /tmp/ft_<name>
#   bash run_ab.sh eval <benchmark>...                   evaluate each run's last checkpoint
OUT_DIR=${OUT_DIR:-out}
export PYTHONUNBUFFERED=1
MOSAIC="natural_ground|random_uniform|pyramid_slope|pyramid_slope:direction=down|pyramid_stairs|pyramid_stairs:direction=down|discrete_obstacles|rocks|waves"
TYPES="['flat', 'random_uniform', 'natural_ground', 'pyramid_slope', 'pyramid_slope:direction=down', 'pyramid_stairs', 'pyramid_stairs:direction=down', 'discrete_obstacles', 'rocks', 'waves', 'river+water', 'basin+water:flow=current,speed=0.5', 'hills+soil:preset=dry_sand', 'soil:preset=mud', 'low_friction', '$MOSAIC']"
PROPS="[0.125, 0.0833, 0.0417, 0.0625, 0.0625, 0.0417, 0.0417, 0.0417, 0.0417, 0.0417, 0.0625, 0.0417, 0.0625, 0.0417, 0.0417, 0.1667]"
COMMON=(--set runner.critic_warmup_iterations=500 --set terrain.max_init_terrain_level=8
        --set terrain.solved_top_level=stay --set terrain.max_difficulty=1.65 --set terrain.num_rows=16
        --set rewards.scales.tracking_lin_vel=5 --set rewards.scales.tracking_ang_vel=4)
MOSAIC_SETS=(--set "terrain.terrain_types=$TYPES" --set "terrain.terrain_proportions=$PROPS" --set terrain.num_cols=24)
DEVICE=${DEVICE_CPU:+--device cpu}
nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null
args_of() {  # the run's own flags
  case $1 in C) echo "--num_envs ${NUM_ENVS_C:-4096}" ;; K) echo "--num_envs ${NUM_ENVS_K:-4915}" ;; esac
}
sets_of() { if [ "$1" = K ]; then printf '%s\n' "${COMMON[@]}" "${MOSAIC_SETS[@]}"; else printf '%s\n' "${COMMON[@]}"; fi; }
last_run() { ls -d /tmp/ft_$1/gente_biped/*/ | tail -1; }
last_ckpt() { ls -v "$1"/model_*.pt | tail -1; }
one() {  # name gpu mode minutes iterations
  local name=$1 gpu=$2 mode=$3 minutes=$4 iters=$5 out="$OUT_DIR/$1" from=""
  mkdir -p "$out"
  mapfile -t sets < <(sets_of "$name")
  if [ "$mode" = resume ]; then
    from=$(last_run "$name"); local n; n=$(basename "$(last_ckpt "$from")" .pt); n=${n#model_}
    iters=$((iters - n)); from="--resume --load_run ${from%/}"
  else from="--pretrained"; fi
  CUDA_VISIBLE_DEVICES=$gpu timeout 590 python -m legged_gente.scripts.train --task gente_biped --headless $(args_of "$name") $DEVICE \
    --max_iterations "$iters" --max_minutes "$minutes" --log_root /tmp/ft_$name $from "${sets[@]}" > "$out/train_$mode.log" 2>&1
  echo "$name rc $?"
  grep -E "Learning iteration|terrain_level|diverged_resets|Time limit|Error|error" "$out/train_$mode.log" | tail -6 | sed "s/^/$name: /"
  gzip -f "$out/train_$mode.log"
  local run; run=$(last_run "$name")
  local base; base=$(basename "${run%/}")
  tar czf "$out/run_$mode.tar.gz" -C "${run%/}/.." "$base/$(basename "$(last_ckpt "$run")")" \
      $(cd "${run%/}/.." && ls -d "$base"/*.json "$base"/events* 2>/dev/null)
  echo "$name packed $(last_ckpt "$run")"
}
evals() {  # name gpu benchmarks...
  local name=$1 gpu=$2 out="$OUT_DIR/$1"; shift 2
  local ckpt; ckpt=$(last_ckpt "$(last_run "$name")")
  for b in "$@"; do
    CUDA_VISIBLE_DEVICES=$gpu timeout 300 python -m legged_gente.scripts.evaluate --task gente_biped --checkpoint "$ckpt" $DEVICE \
      --benchmark "$b" --robots_per_terrain ${ROBOTS:-64} --seed 0 --out "/tmp/ev_${name}_$b" --no_progress > "$out/ev_$b.log" 2>&1
    echo "$name rc $? $b $(basename "$ckpt")"; tail -4 "$out/ev_$b.log" | sed "s/^/$name: /"
    cp "/tmp/ev_${name}_$b/report.csv" "$out/$b.csv"; cp "/tmp/ev_${name}_$b/report.json" "$out/$b.json" 2>/dev/null
  done
}
mode=$1; shift
case $mode in
  train|resume) one C 0 "$mode" "$1" "$2" & one K 1 "$mode" "$1" "$2" & wait ;;
  eval) mkdir -p "$OUT_DIR/C" "$OUT_DIR/K"; evals C 0 "$@" & evals K 1 "$@" & wait ;;
esac
