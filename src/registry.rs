//! The models the tool has, one line each, and the one way to run any of them:
//! [`Model::simulate`] checks what every run needs checked (the budgets, that the model can
//! represent the scene, that the series fits in memory) before the model does any work.

use crate::model::{Checks, ModelError, RunOptions, Setting, Simulator};
use crate::run::{check_memory, Model, Record, Run};
use crate::scene::Scene;

/// The implementation of each model.
fn simulator(model: Model) -> &'static dyn Simulator {
    match model {
        Model::Reference => &crate::reference::Reference,
        Model::Rapier => &crate::rapier::Rapier,
        Model::Compliant => &crate::compliant::Compliant,
    }
}

impl Model {
    /// Runs the model on `scene` under `options`. Refused before any work when a budget breaks
    /// its rule, when the model cannot represent the scene, or when the series it keeps would
    /// not fit in memory. The run (or the run so far) keeps of its impacts what the options
    /// ask; a model whose impacts could outgrow memory counts them as it goes.
    pub fn simulate(self, scene: &Scene, options: &RunOptions) -> Result<Run, ModelError> {
        if let Err((budget, rule)) = options.limits.check() {
            return Err(ModelError::Refused(format!("{}: {rule}", budget.flag().unwrap_or_default())));
        }
        let model = simulator(self);
        model
            .supports(scene)
            .map_err(|reason| ModelError::Refused(format!("scene `{}`: {} cannot run it: {reason}", scene.name, self.title())))?;
        if options.record == Record::Series {
            check_memory(scene).map_err(ModelError::Refused)?;
        }
        let keep = options.impacts;
        let mut run = model.simulate(scene, options).map_err(|e| match e {
            ModelError::OverBudget(mut stop) => {
                stop.partial.keep_impacts(keep);
                ModelError::OverBudget(stop)
            }
            e => e,
        })?;
        run.keep_impacts(keep);
        Ok(run)
    }

    /// Whether the model can represent `scene`: the reason when it cannot.
    pub fn supports(self, scene: &Scene) -> Result<(), String> {
        simulator(self).supports(scene)
    }

    /// The tolerances a run of `scene` by this model is checked with.
    pub fn checks(self, scene: &Scene, run: &Run) -> Checks {
        simulator(self).checks(scene, run)
    }

    /// The scene settings this model reads.
    pub fn settings(self) -> &'static [Setting] {
        simulator(self).settings()
    }

    /// How this model steps on `scene`.
    pub fn stepping(self, scene: &Scene) -> &'static str {
        simulator(self).stepping(scene)
    }
}
